// E57: the file header, the paged file with its CRC-32C, the XML section and the compressed
// vectors' packets and bit-packed fields (io/e57/e57_io.h), read to the end.
#include "fuzz/fuzz_util.h"
#include "io/e57/e57_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.e57", data, size);
  candi::fuzz::ReadToEnd(
      [&](const auto& options) { return candi::io::OpenE57Reader(path, options); });
  return 0;
}
