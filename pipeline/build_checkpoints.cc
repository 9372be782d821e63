#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>

#include "core/atomic_file.h"
#include "core/sha256.h"
#include "core/version.h"
#include "io/point_io.h"
#include "pipeline/build_internal.h"

namespace candi::pipeline::internal {

namespace fs = std::filesystem;
using nlohmann::json;

Checkpoints::Checkpoints(const fs::path& dir, bool resume) : dir_(dir), resume_(resume) {
  fs::create_directories(dir);
}

std::optional<json> Checkpoints::Find(const std::string& stage, const std::string& key,
                                      const std::vector<fs::path>& outputs) const {
  const fs::path file = dir_ / (stage + ".json");
  std::error_code ec;
  if (resume_ && fs::exists(file, ec)) {
    const json j = json::parse(ReadFileToString(file.string()), nullptr, /*allow_exceptions=*/false);
    bool complete = j.is_object() && j.value("key", "") == key;
    for (const fs::path& o : outputs) complete = complete && fs::exists(o, ec);
    if (complete) return j;
  }
  fs::remove(file, ec);
  return std::nullopt;
}

void Checkpoints::Save(const std::string& stage, const std::string& key, json data) const {
  data["key"] = key;
  WriteFileAtomic((dir_ / (stage + ".json")).string(), data.dump(1) + "\n");
  // For tests (tests/fault_test.cc): CANDI_TEST_INTERRUPT_AFTER=<stage> interrupts the build
  // right after this checkpoint, as a user's Ctrl-C would, at a point that no timing decides.
  // The interrupt handler's thread ends the process; this one waits for it.
  const char* interrupt_after = std::getenv("CANDI_TEST_INTERRUPT_AFTER");
  if (interrupt_after != nullptr && stage == interrupt_after) {
    kill(getpid(), SIGINT);
    for (;;) pause();
  }
}

const std::string& FileHashes::operator()(const std::string& path) {
  auto it = hashes_.find(path);
  if (it == hashes_.end()) it = hashes_.emplace(path, Sha256OfFile(path)).first;
  return it->second;
}

std::string FolderFingerprint(const std::string& dir) {
  std::vector<std::string> entries;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const auto mtime = fs::last_write_time(it->path(), ec).time_since_epoch().count();
    entries.push_back(fs::relative(it->path(), dir, ec).string() + " " + std::to_string(it->file_size(ec)) + " " +
                      std::to_string(mtime));
  }
  std::sort(entries.begin(), entries.end());
  std::string text;
  for (const std::string& e : entries) text += e + "\n";
  return Sha256Hex(text);
}

std::string Key(const std::vector<std::string>& parts) {
  std::string text = kVersion;
  for (const std::string& p : parts) text += "\n" + p;
  return Sha256Hex(text);
}

void SaveLayer(const Checkpoints& checkpoints, const std::string& stage, const std::string& key,
               const fs::path& points, const LayerResult& r) {
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat64;
  io::WritePointCloud(points.string(), r.cloud, o);
  checkpoints.Save(stage, key, {{"method", r.method}, {"parameters", r.parameters}, {"seconds", r.seconds}});
}

LayerResult LoadLayer(const json& checkpoint, const fs::path& points) {
  LayerResult r;
  r.cloud = io::ReadPointCloud(points.string());
  r.method = checkpoint.at("method").get<std::string>();
  r.parameters = checkpoint.at("parameters");
  r.seconds = checkpoint.at("seconds").get<double>();
  return r;
}

}  // namespace candi::pipeline::internal
