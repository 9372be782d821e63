// E57: the file header, the paged file with its CRC-32C, the XML section and the compressed
// vectors' packets and bit-packed fields (io/e57/e57_io.h), read to the end.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "io/e57/e57_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.e57", data, size);
  try {
    const std::unique_ptr<candi::io::PointReader> reader = candi::io::OpenE57Reader(path, {});
    candi::PointCloud chunk;
    while (reader->Read(4096, &chunk) > 0) {
    }
  } catch (const candi::InputError&) {
  }
  return 0;
}
