#include "apps/view_json.h"

#include "core/atomic_file.h"
#include "core/check.h"

namespace candi::app {

render::Camera LoadView(const std::string& path) { return render::ParseView(ReadFileToString(path), path); }

void SaveView(const std::string& path, const render::Camera& c) { WriteFileAtomic(path, ViewToJson(c) + "\n"); }

}  // namespace candi::app
