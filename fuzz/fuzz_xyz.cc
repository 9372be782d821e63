// XYZ and PTS text (io/xyz/xyz_io.h): the same bytes read as both, columns guessed.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "io/xyz/xyz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.xyz", data, size);
  for (const bool pts : {false, true}) {
    try {
      const std::unique_ptr<candi::io::PointReader> reader = candi::io::OpenXyzReader(path, pts, {});
      candi::PointCloud chunk;
      while (reader->Read(4096, &chunk) > 0) {
      }
    } catch (const candi::InputError&) {
    }
  }
  return 0;
}
