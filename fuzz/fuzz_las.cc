// LAS: header, VLRs/EVLRs, extra-bytes descriptors and point records (io/las/las_io.h), read to the
// end of the file with and without scalar fields.
#include "fuzz/fuzz_util.h"
#include "io/las/las_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.las", data, size);
  candi::fuzz::ReadToEnd(
      [&](const auto& options) { return candi::io::OpenLasReader(path, options); }, true);
  return 0;
}
