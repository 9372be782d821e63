// PLY: the point reader (core/ply_io.h: header, ascii and binary bodies, every property type) to
// the end of the file, then the mesh reader (faces) on the same bytes.
#include "core/check.h"
#include "core/ply_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.ply", data, size);
  try {
    const std::unique_ptr<candi::PointReader> reader = candi::OpenPlyReader(path);
    candi::PointCloud chunk;
    while (reader->Read(4096, &chunk) > 0) {
    }
  } catch (const candi::InputError&) {
  }
  try {
    candi::ReadPlyMesh(path);
  } catch (const candi::InputError&) {
  }
  return 0;
}
