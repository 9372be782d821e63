#include "fuzz/colmap_model_fuzz.h"

#include "core/check.h"
#include "fuzz/fuzz_util.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::fuzz {

void FuzzColmapModel(const uint8_t* data, size_t size, const char* extension) {
  const std::string dir = FreshScratchFolder("model");
  const char* names[3] = {"cameras", "images", "points3D"};
  const std::vector<std::string_view> parts = SplitParts(data, size, 3);
  for (size_t k = 0; k < parts.size(); ++k) {
    WriteScratchFile(dir + "/" + names[k] + extension, parts[k]);
  }
  try {
    photogrammetry::ReadColmapModel(dir);
  } catch (const InputError&) {
  }
}

}  // namespace candi::fuzz
