// LAZ: the laszip VLR, the chunk table and the compressed chunks of both compressors (pointwise
// v2, layered v3), read to the end through the LAS reader (core/las_io.h, core/laz_format.h),
// with and without scalar fields.
#include "core/check.h"
#include "core/point_io.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.laz", data, size);
  for (const bool scalar_fields : {true, false}) {
    try {
      candi::PointReadOptions options;
      options.scalar_fields = scalar_fields;
      const std::unique_ptr<candi::PointReader> reader = candi::OpenPointReader(path, options);
      candi::PointCloud chunk;
      while (reader->Read(4096, &chunk) > 0) {
      }
    } catch (const candi::InputError&) {
    }
  }
  return 0;
}
