// candi_docs_runner SOURCE_DIR CANDI_DIR DOC: runs the shell blocks of one document of docs/, so
// that the guide cannot rot. tests/CMakeLists.txt registers one ctest test per docs/**/*.md file,
// `docs_blocks.docs/<page>.md` (label docs; part of `make test`).
//
// The conventions (docs/CONTRIBUTING-docs.md says the same for the docs' writers):
//  - ```sh blocks are run, in document order, each by its own `bash -euo pipefail`, in a temporary
//    working directory shared by the document's blocks (a later block may use an earlier block's
//    outputs) and removed afterwards (kept, with the block scripts and logs, when
//    CANDI_DOCS_KEEP=1). `candi` is on PATH (the build's apps/ folder first). In the working
//    directory, `examples` is a symlink to the repository's examples/, and `data` one to
//    ../shared/data beside the repository when that exists. stdin is /dev/null; processes a block
//    leaves running are killed when it ends.
//  - A ```sh block whose first line is `# needs: shared-data` is skipped (reported, not failed)
//    when ../shared/data is absent. A block using the outputs of such a block needs the same line.
//  - ```sh-norun blocks are not run; their first line must be `# not run: <reason>` (the test fails
//    without it).
//  - Other info strings (text, console, json, ...) are not commands and are not run. A block marked
//    `bash` or `shell`, or with no info string, that has a line starting with `candi ` or
//    `$ candi ` (not indented relative to the fence) fails the test: a command is either run (sh)
//    or marked not runnable (sh-norun).
//  - A document's blocks share a time budget, CANDI_DOCS_TIMEOUT seconds (default 300); a block
//    still running when it is spent is stopped and fails the test.
//  - A failing block fails the test with the document, the line of the block's opening fence, its
//    exit status and the last lines of its output; the blocks after it are not run.
// Exit status: 0 passed; 1 failed; 77 every ```sh block was skipped (ctest SKIP_RETURN_CODE);
// 2 usage. CANDI_DOCS_SHARED_DATA overrides the shared data folder (tests set it to an absent one).
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "tests/docs/markdown.h"

namespace fs = std::filesystem;
using candi::testing::FencedBlock;
using candi::testing::MarkdownDocument;

namespace {

constexpr int kPassed = 0, kFailed = 1, kUsage = 2, kAllSkipped = 77;
constexpr int kOutputTailLines = 40;

std::string FirstLine(const FencedBlock& b) { return b.lines.empty() ? "" : b.lines.front(); }

bool NeedsSharedData(const FencedBlock& b) {
  static const std::regex re(R"(^\s*#\s*needs:\s*shared-data\s*$)");
  return std::regex_match(FirstLine(b), re);
}

// True for a line that runs candi: `candi ...` or `$ candi ...` at its start (an indented line is
// taken for a diagram or continuation; the fence's own indentation is already removed).
bool RunsCandi(const std::string& line) {
  static const std::regex re(R"(^(\$\s+)?candi(\s.*)?$)");
  return std::regex_match(line, re);
}

// The document's convention violations, each "doc:line: what".
std::vector<std::string> CheckBlocks(const MarkdownDocument& doc, const std::string& name) {
  static const std::regex reason(R"(^\s*#\s*not run:\s*\S.*$)");
  std::vector<std::string> errors;
  for (const FencedBlock& b : doc.blocks) {
    const std::string where = name + ":" + std::to_string(b.line) + ": ";
    if (!b.closed) errors.push_back(where + "the code block is never closed");
    if (b.info == "sh-norun" && !std::regex_match(FirstLine(b), reason)) {
      errors.push_back(where +
                       "a ```sh-norun block must start with the line `# not run: <reason>`");
    }
    if (b.info == "bash" || b.info == "shell" || b.info.empty()) {
      for (const std::string& line : b.lines) {
        if (!RunsCandi(line)) continue;
        errors.push_back(where + "a ```" + (b.info.empty() ? "" : b.info) + " block runs `" + line +
                         "`: mark it ```sh to have it tested, or ```sh-norun with `# not run: "
                         "<reason>`");
        break;
      }
    }
  }
  return errors;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The last `count` lines of `text`.
std::string Tail(const std::string& text, int count) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  if (lines.empty()) return "(no output)";
  std::string tail;
  for (size_t i = lines.size() > static_cast<size_t>(count) ? lines.size() - count : 0;
       i < lines.size(); ++i) {
    tail += lines[i] + "\n";
  }
  return tail;
}

struct BlockRun {
  int status = -1;  // bash's exit status, or -1 when killed
  bool timed_out = false;
};

// Runs `bash -euo pipefail script` in `work`, output to `log`, in its own process group, stopped
// after `seconds`.
BlockRun RunScript(const fs::path& script, const fs::path& work, const fs::path& log,
                   double seconds) {
  BlockRun run;
  const pid_t pid = fork();
  if (pid < 0) return run;
  if (pid == 0) {
    setpgid(0, 0);
    const int out = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int in = open("/dev/null", O_RDONLY);
    if (out < 0 || in < 0 || chdir(work.c_str()) != 0) _exit(126);
    dup2(in, 0);
    dup2(out, 1);
    dup2(out, 2);
    execl("/bin/bash", "bash", "-e", "-u", "-o", "pipefail", script.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  setpgid(pid, pid);
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  int status = 0;
  bool terminated = false;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (!terminated && elapsed() > seconds) {
      run.timed_out = true;
      terminated = true;
      kill(-pid, SIGTERM);  // candi removes its unfinished outputs on SIGTERM
    } else if (terminated && elapsed() > seconds + 10) {
      kill(-pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(-pid, SIGKILL);  // whatever the block left running in the background
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

// A fresh directory under $TMPDIR.
fs::path MakeTempDir() {
  const char* tmp = std::getenv("TMPDIR");
  std::string pattern = std::string(tmp && *tmp ? tmp : "/tmp") + "/candi-docs-XXXXXX";
  std::vector<char> buf(pattern.begin(), pattern.end());
  buf.push_back('\0');
  if (mkdtemp(buf.data()) == nullptr) {
    std::cerr << "candi_docs_runner: cannot create a directory " << pattern << ": "
              << std::strerror(errno) << "\n";
    std::exit(kFailed);
  }
  return buf.data();
}

double BudgetSeconds() {
  const char* v = std::getenv("CANDI_DOCS_TIMEOUT");
  const double s = v && *v ? std::atof(v) : 300.0;
  return s > 0 ? s : 300.0;
}

fs::path SharedData(const fs::path& source_dir) {
  const char* v = std::getenv("CANDI_DOCS_SHARED_DATA");
  const fs::path path = v ? fs::path(v) : source_dir / ".." / "shared" / "data";
  std::error_code ec;
  return !path.empty() && fs::is_directory(path, ec) ? fs::canonical(path) : fs::path();
}

struct Counts {
  int run = 0, skipped = 0, not_run = 0;
};

// Runs the document's ```sh blocks in `work`; false when one fails (reported on stdout).
bool RunBlocks(const MarkdownDocument& doc, const std::string& name, const fs::path& root,
               const fs::path& work, bool have_data, Counts& counts) {
  const double budget = BudgetSeconds();
  const auto start = std::chrono::steady_clock::now();
  for (size_t i = 0; i < doc.blocks.size(); ++i) {
    const FencedBlock& b = doc.blocks[i];
    const std::string where = name + ":" + std::to_string(b.line);
    if (b.info != "sh") continue;
    if (NeedsSharedData(b) && !have_data) {
      std::cout << "SKIPPED " << where << ": needs shared-data, and ../shared/data is absent\n";
      ++counts.skipped;
      continue;
    }
    const fs::path script = root / ("block_line" + std::to_string(b.line) + ".sh");
    const fs::path log = root / ("block_line" + std::to_string(b.line) + ".log");
    std::ofstream(script) << [&] {
      std::string text;
      for (const std::string& line : b.lines) text += line + "\n";
      return text;
    }();
    const double used =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto block_start = std::chrono::steady_clock::now();
    const BlockRun run = RunScript(script, work, log, budget - used);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - block_start).count();
    ++counts.run;
    if (run.status == 0 && !run.timed_out) {
      std::printf("ok      %s (%.1f s)\n", where.c_str(), seconds);
      continue;
    }
    std::cout << "FAILED  " << where << ": the ```sh block starting `" << FirstLine(b) << "` ";
    if (run.timed_out) {
      std::cout << "was stopped: the document's blocks ran past their " << budget
                << " s (CANDI_DOCS_TIMEOUT)\n";
    } else if (run.status < 0) {
      std::cout << "was killed by a signal\n";
    } else {
      std::cout << "exited with status " << run.status << "\n";
    }
    std::cout << "--- the last " << kOutputTailLines << " lines of its output ---\n"
              << Tail(ReadFile(log), kOutputTailLines) << "---\n";
    const size_t left = static_cast<size_t>(
        std::count_if(doc.blocks.begin() + static_cast<std::ptrdiff_t>(i) + 1, doc.blocks.end(),
                      [](const FencedBlock& x) { return x.info == "sh"; }));
    if (left > 0) std::cout << left << " later ```sh block(s) of " << name << " not run\n";
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: candi_docs_runner SOURCE_DIR CANDI_DIR DOC (DOC relative to SOURCE_DIR)\n";
    return kUsage;
  }
  const fs::path source_dir = fs::absolute(argv[1]);
  const fs::path candi_dir = fs::absolute(argv[2]);
  const std::string name = argv[3];
  const fs::path doc_path = source_dir / name;
  std::error_code ec;
  if (!fs::is_regular_file(doc_path, ec)) {
    std::cout << "FAILED  " << name << ": no such document\n";
    return kFailed;
  }
  const MarkdownDocument doc = candi::testing::ParseMarkdown(ReadFile(doc_path));
  const std::vector<std::string> errors = CheckBlocks(doc, name);
  for (const std::string& e : errors) std::cout << "FAILED  " << e << "\n";
  if (!errors.empty()) return kFailed;

  const fs::path root = MakeTempDir();
  const fs::path work = root / "work";
  fs::create_directory(work);
  if (fs::is_directory(source_dir / "examples", ec))
    fs::create_directory_symlink(source_dir / "examples", work / "examples");
  const fs::path data = SharedData(source_dir);
  if (!data.empty()) fs::create_directory_symlink(data, work / "data");
  const char* path = std::getenv("PATH");
  setenv("PATH", (candi_dir.string() + ":" + (path ? path : "/usr/bin:/bin")).c_str(), 1);

  Counts counts;
  counts.not_run =
      static_cast<int>(std::count_if(doc.blocks.begin(), doc.blocks.end(),
                                     [](const FencedBlock& b) { return b.info == "sh-norun"; }));
  const bool passed = RunBlocks(doc, name, root, work, !data.empty(), counts);
  const char* keep = std::getenv("CANDI_DOCS_KEEP");
  if (keep && std::string(keep) == "1") {
    std::cout << "kept the working directory: " << work.string() << "\n";
  } else {
    fs::remove_all(root, ec);
  }
  std::cout << name << ": " << counts.run << " ```sh block(s) run, " << counts.skipped
            << " skipped, " << counts.not_run << " ```sh-norun\n";
  if (!passed) {
    std::cout << "rerun: CANDI_DOCS_KEEP=1 ctest --test-dir BUILD_DIR -R 'docs_blocks." << name
              << "' --output-on-failure\n";
    return kFailed;
  }
  return counts.run == 0 && counts.skipped > 0 ? kAllSkipped : kPassed;
}
