// The docs code-block runner (tests/docs/docs_runner.cc) on documents written here: what it runs,
// skips and refuses, and how it reports a failing block.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <string>

#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;

// A repository of one document, docs/<name>, and examples/hello.txt.
class DocsRunner : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(fs::path(repo_.path()) / "docs");
    fs::create_directories(fs::path(repo_.path()) / "examples");
    WriteBytes(repo_.File("examples/hello.txt"), "hello from examples\n");
  }

  // Runs the runner on `text` as docs/<name>, with `env` (VAR=value ...) before it.
  CommandResult Run(const std::string& name, const std::string& text, const std::string& env = "") {
    WriteBytes(repo_.File("docs/" + name), text);
    const std::string candi_dir = fs::path(CANDI_EXECUTABLE).parent_path().string();
    return testing::RunCommand("env CANDI_DOCS_SHARED_DATA=" + data_.path() + " " + env + " " +
                               CANDI_DOCS_RUNNER + " " + repo_.path() + " " + candi_dir + " docs/" +
                               name);
  }

  TempDir repo_;
  TempDir data_;  // the shared data: present, empty
};

TEST_F(DocsRunner, RunsShBlocksInOrderInOneDirectoryAndNothingElse) {
  WriteBytes(data_.File("survey.txt"), "x\n");
  const CommandResult r = Run("guide.md",
                              "# Guide\n"
                              "```sh\n"
                              "candi --version > version.txt\n"
                              "grep -q hello examples/hello.txt\n"
                              "```\n"
                              "Then:\n"
                              "```sh\n"
                              "# needs: shared-data\n"
                              "grep -q 'candi 0.' version.txt && test -f data/survey.txt\n"
                              "```\n"
                              "```sh-norun\n"
                              "# not run: opens a browser and serves until stopped\n"
                              "candi view archive/\n"
                              "```\n"
                              "```console\n$ candi info site.las\n```\n"
                              "```json\n{\"candi info\": false}\n```\n"
                              "```text\ncandi info is not run from here\n```\n");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("ok      docs/guide.md:2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ok      docs/guide.md:7"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("2 ```sh block(s) run, 0 skipped, 1 ```sh-norun"), std::string::npos)
      << r.out;
}

TEST_F(DocsRunner, AFailingBlockNamesTheDocumentLineAndOutputTail) {
  const CommandResult r = Run("bad.md",
                              "```sh\necho fine\n```\n"
                              "\n"
                              "```sh\n"
                              "echo 'the tail of the output' >&2\n"
                              "candi info no_such_file.ply\n"
                              "echo never\n"
                              "```\n"
                              "```sh\necho later\n```\n");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(
      r.out.find(
          "FAILED  docs/bad.md:5: the ```sh block starting `echo 'the tail of the output' >&2` "
          "exited with status 2"),
      std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("the tail of the output"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no_such_file.ply"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("never"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 later ```sh block(s) of docs/bad.md not run"), std::string::npos)
      << r.out;
}

TEST_F(DocsRunner, BlocksRunWithErrexitNounsetAndPipefail) {
  EXPECT_EQ(Run("a.md", "```sh\nfalse | cat\n```\n").code, 1);
  EXPECT_EQ(Run("b.md", "```sh\necho \"$NO_SUCH_VARIABLE\"\n```\n").code, 1);
  EXPECT_EQ(Run("c.md", "```sh\nfalse\necho still running\n```\n").code, 1);
}

TEST_F(DocsRunner, NorunBlocksNeedTheirReason) {
  const CommandResult r = Run("norun.md", "text\n\n```sh-norun\ncandi view archive/\n```\n");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(
      r.out.find(
          "docs/norun.md:3: a ```sh-norun block must start with the line `# not run: <reason>`"),
      std::string::npos)
      << r.out;
  EXPECT_EQ(Run("norun2.md", "```sh-norun\n# not run:\ncandi view archive/\n```\n").code, 1)
      << "an empty reason";
}

TEST_F(DocsRunner, UnmarkedCommandBlocksFail) {
  CommandResult r = Run("bash.md", "```bash\ncd work\ncandi info site.las\n```\n");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.out.find("docs/bash.md:1: a ```bash block runs `candi info site.las`"),
            std::string::npos)
      << r.out;
  r = Run("shell.md", "```shell\ncandi demo -o out\n```\n");
  EXPECT_EQ(r.code, 1) << r.output;
  r = Run("plain.md", "para\n```\n$ candi render a.ply -o a.png\n```\n");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.out.find("docs/plain.md:2: a ``` block runs"), std::string::npos) << r.out;
  // In a list item, the fence's indentation is not the line's.
  EXPECT_EQ(Run("list.md", "- item:\n\n  ```bash\n  candi info a.ply\n  ```\n").code, 1);
  // Not commands: a bash block without candi, candi mid-line or indented (a diagram).
  EXPECT_EQ(Run("ok.md",
                "```bash\nexport X=1\n```\n```\nrun candi info first\n   candi build: "
                "layers -> archive\n```\n")
                .code,
            0);
}

TEST_F(DocsRunner, SharedDataBlocksAreSkippedWithoutTheData) {
  const std::string text = "```sh\n# needs: shared-data\nls data/\n```\n";
  CommandResult r = Run("data.md", text, "CANDI_DOCS_SHARED_DATA=" + repo_.File("absent"));
  EXPECT_EQ(r.code, 77) << r.output;  // every block skipped: ctest reports the test skipped
  EXPECT_NE(r.out.find("SKIPPED docs/data.md:1: needs shared-data"), std::string::npos) << r.out;
  r = Run("mixed.md", text + "```sh\ntest ! -e data\n```\n",
          "CANDI_DOCS_SHARED_DATA=" + repo_.File("absent"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(Run("data2.md", text).code, 0) << "the data is present";
}

TEST_F(DocsRunner, ADocumentPastItsTimeBudgetFails) {
  const auto start = std::chrono::steady_clock::now();
  const CommandResult r =
      Run("slow.md", "```sh\nsleep 1\n```\n```sh\nsleep 60 | cat\n```\n", "CANDI_DOCS_TIMEOUT=2");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(
      r.out.find("FAILED  docs/slow.md:4: the ```sh block starting `sleep 60 | cat` was stopped"),
      std::string::npos)
      << r.out;
  EXPECT_LT(seconds, 30);
}

TEST_F(DocsRunner, AnUnclosedBlockFails) {
  const CommandResult r = Run("open.md", "# T\n```sh\necho hi\n");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.out.find("docs/open.md:2: the code block is never closed"), std::string::npos)
      << r.out;
}

}  // namespace
}  // namespace candi::testing
