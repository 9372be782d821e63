#include "apps/output_folder.h"

#include <unistd.h>

#include <filesystem>
#include <system_error>

#include "core/check.h"

namespace candi::app {

void CheckOutputFolder(const std::string& output) {
  std::filesystem::path folder = std::filesystem::path(output).parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) {
    throw InputError(output, "", "output folder '" + folder.string() + "' " +
                                     (std::filesystem::exists(folder, ec) ? "is not a folder" : "does not exist"));
  }
  if (::access(folder.c_str(), W_OK) != 0) {
    throw InputError(output, "", "output folder '" + folder.string() + "' is not writable");
  }
}

}  // namespace candi::app
