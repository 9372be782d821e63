#include "io/shift_sidecar.h"

#include <sys/stat.h>

#include <cstdio>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"

namespace candi::io {

std::string ShiftSidecarPath(const std::string& path) { return path + ".shift.json"; }

void WriteShiftSidecar(const std::string& path, const LocalFrame& frame) {
  struct stat st;
  const uint64_t size = stat(path.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
  const std::string json = "{\n  \"candi_shift\": [" + FormatDouble(frame.origin.x()) + ", " +
                           FormatDouble(frame.origin.y()) + ", " + FormatDouble(frame.origin.z()) +
                           "],\n  \"meaning\": \"world = local + candi_shift (metres)\",\n" +
                           "  \"file_size\": " + std::to_string(size) + "\n}\n";
  WriteFileAtomic(ShiftSidecarPath(path), json);
}

std::optional<LocalFrame> ReadShiftSidecar(const std::string& path) {
  const std::string sidecar = ShiftSidecarPath(path);
  struct stat st, st_data;
  if (stat(sidecar.c_str(), &st) != 0 || stat(path.c_str(), &st_data) != 0) return std::nullopt;
  const std::string text = ReadFileToString(sidecar);
  const size_t key = text.find("\"candi_shift\"");
  const size_t size_key = text.find("\"file_size\"");
  if (key == std::string::npos || size_key == std::string::npos) {
    throw InputError(sidecar, "", "not a candi shift sidecar (no \"candi_shift\" / \"file_size\")");
  }
  double x, y, z;
  unsigned long long size = 0;
  const size_t open = text.find('[', key);
  if (open == std::string::npos ||
      std::sscanf(text.c_str() + open, "[ %lf , %lf , %lf ]", &x, &y, &z) != 3 ||
      std::sscanf(text.c_str() + text.find(':', size_key) + 1, " %llu", &size) != 1) {
    throw InputError(sidecar, "", "malformed candi_shift or file_size");
  }
  if (size != static_cast<unsigned long long>(st_data.st_size)) return std::nullopt;  // stale
  LocalFrame frame;
  frame.origin = Eigen::Vector3d(x, y, z);
  if (!frame.origin.allFinite()) throw InputError(sidecar, "", "candi_shift is not finite");
  return frame;
}

}  // namespace candi::io
