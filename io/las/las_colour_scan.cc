#include "io/las/las_colour_scan_internal.h"

#include <sys/stat.h>

#include <map>
#include <mutex>
#include <tuple>

namespace candi::io {

bool CachedWideColours(const std::string& path, const std::function<bool()>& scan) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return scan();  // a pipe: each read differs
  using Key = std::tuple<std::string, int64_t, int64_t, int64_t>;  // path, size, mtime s, ns
  const Key key{path, static_cast<int64_t>(st.st_size), static_cast<int64_t>(st.st_mtim.tv_sec),
                static_cast<int64_t>(st.st_mtim.tv_nsec)};
  static std::mutex mutex;
  static std::map<Key, bool> answers;
  {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = answers.find(key);
    if (it != answers.end()) return it->second;
  }
  const bool wide = scan();  // outside the lock: other files are scanned meanwhile
  std::lock_guard<std::mutex> lock(mutex);
  answers[key] = wide;
  return wide;
}

}  // namespace candi::io
