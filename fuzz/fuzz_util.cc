#include "fuzz/fuzz_util.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "core/check.h"
#include "core/log.h"
#include "core/point_cloud.h"

namespace candi::fuzz {

namespace {

std::string MakeScratchDir() {
  std::string base = "/dev/shm";
  std::error_code ec;
  if (!std::filesystem::is_directory(base, ec) || access(base.c_str(), W_OK) != 0) {
    const char* tmp = std::getenv("TMPDIR");
    base = tmp && *tmp ? tmp : "/tmp";
  }
  const std::string dir = base + "/candi-fuzz-" + std::to_string(getpid());
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir);
  return dir;
}

// candi's warnings ("skipped 3 faces", guessed columns) would print on most inputs: silenced.
const bool kQuietLog = (SetLogSink([](LogLevel, const std::string&) {}), true);

struct Scratch {
  std::string dir = MakeScratchDir();
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

}  // namespace

const std::string& ScratchDir() {
  static const Scratch scratch;
  return scratch.dir;
}

void WriteScratchFile(const std::string& path, std::string_view bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) throw std::runtime_error("fuzz: cannot write " + path);
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  if (std::fclose(f) != 0 || !ok) throw std::runtime_error("fuzz: cannot write " + path);
}

std::string WriteScratchFile(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = ScratchDir() + "/" + name;
  WriteScratchFile(path, std::string_view(reinterpret_cast<const char*>(data), size));
  return path;
}

void RemoveScratchFile(const std::string& name) {
  std::error_code ec;
  std::filesystem::remove(ScratchDir() + "/" + name, ec);
}

std::string FreshScratchFolder(const std::string& name) {
  const std::string dir = ScratchDir() + "/" + name;
  std::error_code ec;
  std::filesystem::remove_all(dir, ec);
  std::filesystem::create_directories(dir);
  return dir;
}

std::vector<std::string_view> SplitParts(const uint8_t* data, size_t size, size_t max_parts) {
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  std::vector<std::string_view> parts;
  while (parts.size() + 1 < max_parts) {
    const size_t at = rest.find(kFuzzPartSeparator);
    if (at == std::string_view::npos) break;
    parts.push_back(rest.substr(0, at));
    rest.remove_prefix(at + kFuzzPartSeparator.size());
  }
  parts.push_back(rest);
  return parts;
}

void ReadToEnd(const ReaderOpener& open, bool also_without_scalar_fields) {
  io::PointReadOptions options;
  for (const bool scalar_fields : {true, false}) {
    if (!scalar_fields && !also_without_scalar_fields) break;
    options.scalar_fields = scalar_fields;
    try {
      const std::unique_ptr<io::PointReader> reader = open(options);
      PointCloud chunk;
      while (reader->Read(4096, &chunk) > 0) {
      }
    } catch (const InputError&) {
    }
  }
}

}  // namespace candi::fuzz
