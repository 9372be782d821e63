#include "tests/util/test_util.h"

#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace candi::testing {

std::string SourceDir() { return CANDI_SOURCE_DIR; }

std::string SharedDataPath(const std::string& relative) {
  const std::string path = SourceDir() + "/../shared/data/" + relative;
  return FileExists(path) ? path : "";
}

std::string NodeWith(const std::string& package, std::string* why) {
  const std::string node = "NODE_PATH='" + SourceDir() + "/.cache/node/node_modules' node";
  if (std::system("command -v node > /dev/null 2>&1") != 0) {
    *why = "node is not installed (scripts/deps.sh installs Debian's nodejs)";
    return "";
  }
  if (std::system((node + " -e \"require('" + package + "')\" > /dev/null 2>&1").c_str()) != 0) {
    *why = "npm's " + package + " is not in .cache/node (scripts/deps.sh installs tests/node/package.json; it " +
           "needs the npm registry)";
    return "";
  }
  return node;
}

FileSizeLimit::FileSizeLimit(uint64_t bytes) {
  struct rlimit limit;
  getrlimit(RLIMIT_FSIZE, &limit);
  old_soft_ = limit.rlim_cur;
  old_handler_ = signal(SIGXFSZ, SIG_IGN);
  limit.rlim_cur = bytes;
  setrlimit(RLIMIT_FSIZE, &limit);
}

FileSizeLimit::~FileSizeLimit() {
  struct rlimit limit;
  getrlimit(RLIMIT_FSIZE, &limit);
  limit.rlim_cur = old_soft_;
  setrlimit(RLIMIT_FSIZE, &limit);
  signal(SIGXFSZ, old_handler_);
}

TempDir::TempDir() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/candi-test-XXXXXX";
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  if (mkdtemp(buf.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  path_ = buf.data();
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::permissions(path_, std::filesystem::perms::owner_all,
                               std::filesystem::perm_options::add, ec);
  std::filesystem::remove_all(path_, ec);
}

CommandResult RunCommand(const std::string& command) {
  TempDir dir;
  const std::string err = dir.File("stderr");
  FILE* pipe = popen((command + " 2>" + err).c_str(), "r");
  CommandResult r;
  if (pipe == nullptr) return r;
  char buf[4096];
  size_t n;
  while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.output = r.out + ReadBytes(err);
  return r;
}

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path);
}

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool FileExists(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0;
}

bool SlowTestsEnabled() {
  const char* v = std::getenv("CANDI_SLOW_TESTS");
  return v != nullptr && std::string(v) == "1";
}

}  // namespace candi::testing
