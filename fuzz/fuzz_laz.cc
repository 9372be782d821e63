// LAZ: the laszip VLR, the chunk table and the compressed chunks of both compressors (pointwise
// v2, layered v3), read to the end through the LAS reader (io/las/las_io.h, io/laz/laz_format.h),
// with and without scalar fields.
#include "fuzz/fuzz_util.h"
#include "io/point_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.laz", data, size);
  candi::fuzz::ReadToEnd(
      [&](const auto& options) { return candi::io::OpenPointReader(path, options); }, true);
  return 0;
}
