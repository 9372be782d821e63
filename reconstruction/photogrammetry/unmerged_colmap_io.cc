// TEMPORARY (branch h2): weak placeholders for colmap_model.h's file functions, which helper h1
// implements on its branch, so that `candi` links before that merge. Weak definitions lose to
// h1's strong ones at link time; delete this file once colmap_model.cc is merged.
#include <string>

#include "core/check.h"
#include "reconstruction/photogrammetry/colmap_model.h"

namespace candi::photogrammetry {

namespace {
[[noreturn]] void Unmerged(const std::string& path) {
  throw InputError(path, "", "COLMAP model/array I/O is not in this build yet (colmap_model.cc)");
}
}  // namespace

__attribute__((weak)) ColmapModel ReadColmapModel(const std::string& dir) { Unmerged(dir); }
__attribute__((weak)) void WriteColmapModelBinary(const ColmapModel&, const std::string& dir) {
  Unmerged(dir);
}
__attribute__((weak)) void WriteColmapModelText(const ColmapModel&, const std::string& dir) {
  Unmerged(dir);
}
__attribute__((weak)) ColmapArray ReadColmapArray(const std::string& path) { Unmerged(path); }
__attribute__((weak)) void WriteColmapArray(const ColmapArray&, const std::string& path) {
  Unmerged(path);
}

}  // namespace candi::photogrammetry
