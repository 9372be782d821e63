// COLMAP binary sparse models (cameras.bin, images.bin, points3D.bin): ReadColmapModel.
#include "fuzz/colmap_model_fuzz.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  candi::fuzz::FuzzColmapModel(data, size, ".bin");
  return 0;
}
