// LAZ: the laszip VLR, the chunk table and the compressed chunks of both compressors (pointwise
// v2, layered v3), read to the end through the LAS reader (io/las/las_io.h, io/las/laz_format.h),
// with and without scalar fields.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "io/point_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.laz", data, size);
  for (const bool scalar_fields : {true, false}) {
    try {
      candi::io::PointReadOptions options;
      options.scalar_fields = scalar_fields;
      const std::unique_ptr<candi::io::PointReader> reader = candi::io::OpenPointReader(path, options);
      candi::PointCloud chunk;
      while (reader->Read(4096, &chunk) > 0) {
      }
    } catch (const candi::InputError&) {
    }
  }
  return 0;
}
