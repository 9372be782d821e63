// PLY: the point reader (io/ply/ply_io.h: header, ascii and binary bodies, every property type) to
// the end of the file, then the mesh reader (faces) on the same bytes.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "io/ply/ply_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.ply", data, size);
  candi::fuzz::ReadToEnd(
      [&](const auto& options) { return candi::io::OpenPlyReader(path, options); });
  try {
    candi::io::ReadPlyMesh(path);
  } catch (const candi::InputError&) {
  }
  return 0;
}
