// The scene file of `candi build` (pipeline/scene.h LoadScene): JSON, layers, views, transforms. Files
// the scene names are looked up beside it (in the scratch folder) and are mostly absent.
#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "pipeline/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = candi::fuzz::WriteScratchFile("scene.json", data, size);
  try {
    candi::pipeline::LoadScene(path);
  } catch (const candi::InputError&) {
  }
  return 0;
}
