// LAS: header, VLRs/EVLRs, extra-bytes descriptors and point records (io/las/las_io.h), read to the
// end of the file with and without scalar fields.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "io/las/las_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.las", data, size);
  for (const bool scalar_fields : {true, false}) {
    try {
      candi::io::PointReadOptions options;
      options.scalar_fields = scalar_fields;
      const std::unique_ptr<candi::io::PointReader> reader = candi::io::OpenLasReader(path, options);
      candi::PointCloud chunk;
      while (reader->Read(4096, &chunk) > 0) {
      }
    } catch (const candi::InputError&) {
    }
  }
  return 0;
}
