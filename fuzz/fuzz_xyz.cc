// XYZ and PTS text (io/xyz/xyz_io.h): the same bytes read as both, columns guessed.
#include "fuzz/fuzz_util.h"
#include "io/xyz/xyz_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.xyz", data, size);
  for (const bool pts : {false, true}) {
    candi::fuzz::ReadToEnd(
        [&](const auto& options) { return candi::io::OpenXyzReader(path, pts, options); });
  }
  return 0;
}
