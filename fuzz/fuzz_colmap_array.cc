// COLMAP dense-workspace arrays (depth and normal maps, "W&H&C&" + float32):
// ReadColmapArray of reconstruction/photogrammetry/sfm/colmap_model.h.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("input.bin", data, size);
  try {
    const candi::photogrammetry::ColmapArray array = candi::photogrammetry::ReadColmapArray(path);
    // Touch the last value through the accessor, as users of the array do.
    volatile float last = array.at(array.width - 1, array.height - 1, array.channels - 1);
    (void)last;
  } catch (const candi::InputError&) {
  }
  return 0;
}
