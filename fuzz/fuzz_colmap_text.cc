// COLMAP text sparse models (cameras.txt, images.txt, points3D.txt): ReadColmapModel.
#include "fuzz/colmap_model_fuzz.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  candi::fuzz::FuzzColmapModel(data, size, ".txt");
  return 0;
}
