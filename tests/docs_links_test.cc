// The docs' links: every relative link and image in README.md and docs/**/*.md names a file or
// folder of the repository. http(s):// and mailto: links are not checked, #anchors are ignored, and
// links inside fenced code blocks or inline code are not links (tests/docs/markdown.h).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "tests/docs/markdown.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;

// README.md and docs/**/*.md, relative to the repository.
std::vector<fs::path> Documents(const fs::path& root) {
  std::vector<fs::path> docs = {"README.md"};
  if (fs::is_directory(root / "docs")) {
    for (const auto& entry : fs::recursive_directory_iterator(root / "docs")) {
      if (entry.is_regular_file() && entry.path().extension() == ".md") {
        docs.push_back(fs::relative(entry.path(), root));
      }
    }
  }
  std::sort(docs.begin() + 1, docs.end());
  return docs;
}

// "" when `target`, linked from `doc`, resolves inside the repository; otherwise what is wrong.
std::string LinkProblem(const fs::path& root, const fs::path& doc, const std::string& target) {
  const std::string path = RelativeLinkPath(target);
  if (path.empty()) return "";
  const fs::path resolved =
      (path[0] == '/' ? root / path.substr(1) : root / doc.parent_path() / path).lexically_normal();
  const fs::path inside = resolved.lexically_relative(root);
  if (inside.empty() || *inside.begin() == "..") return "points outside the repository";
  if (!fs::exists(resolved)) return "no such file: " + inside.string();
  return "";
}

TEST(DocsLinks, EveryRelativeLinkAndImageResolves) {
  const fs::path root = fs::path(testing::SourceDir()).lexically_normal();
  int checked = 0;
  for (const fs::path& doc : Documents(root)) {
    for (const testing::MarkdownLink& link :
         MarkdownLinks(ParseMarkdown(ReadBytes((root / doc).string())))) {
      ++checked;
      const std::string problem = LinkProblem(root, doc, link.target);
      if (!problem.empty()) {
        ADD_FAILURE() << doc.string() << ":" << link.line << ": broken link (" << link.target
                      << "): " << problem;
      }
    }
  }
  EXPECT_GT(checked, 0) << "no links found in README.md and docs/";
}

TEST(DocsLinks, FindsLinksOutsideCodeOnly) {
  const std::string text =
      "See [the guide](docs/guide.md#start) and ![logo](img/logo.png \"Logo\").\n"  // 1
      "[![badge](badge.svg)](https://example.org) `[not](a/link.md)`\n"             // 2
      "```sh\n"                                                                     // 3
      "echo '[no](link.md)'\n"                                                      // 4
      "```\n"                                                                       // 5
      "[ref]: <docs/with space.md>\n"                                               // 6
      "<img src=\"pic.png\"> [x](<a b.md>) [mail](mailto:a@b.c)\n"                  // 7
      "~~~~\n```\n[no](in/tilde.md)\n~~~~\n"                                        // 8-11
      "  ```text\n  [no](indented.md)\n  ```\n"                                     // 12-14
      "[after](after.md)\n";                                                        // 15
  std::vector<std::pair<int, std::string>> got;
  for (const auto& l : MarkdownLinks(ParseMarkdown(text))) got.push_back({l.line, l.target});
  const std::vector<std::pair<int, std::string>> want = {{1, "docs/guide.md#start"},
                                                         {1, "img/logo.png"},
                                                         {2, "badge.svg"},
                                                         {2, "https://example.org"},
                                                         {6, "docs/with space.md"},
                                                         {7, "a b.md"},
                                                         {7, "mailto:a@b.c"},
                                                         {7, "pic.png"},
                                                         {15, "after.md"}};
  EXPECT_EQ(got, want);
  EXPECT_EQ(RelativeLinkPath("docs/guide.md#start"), "docs/guide.md");
  EXPECT_EQ(RelativeLinkPath("#start"), "");
  EXPECT_EQ(RelativeLinkPath("HTTPS://x.org/a.md"), "");
  EXPECT_EQ(RelativeLinkPath("a%20b.md?x=1"), "a b.md");
}

TEST(DocsLinks, ReportsMissingFilesAndLinksOutOfTheRepository) {
  testing::TempDir dir;
  const fs::path root = dir.path();
  fs::create_directories(root / "docs" / "reference");
  testing::WriteBytes((root / "docs" / "reference" / "a.md").string(), "");
  EXPECT_EQ(LinkProblem(root, "docs/guide.md", "reference/a.md#x"), "");
  EXPECT_EQ(LinkProblem(root, "docs/guide.md", "reference/"), "");
  EXPECT_EQ(LinkProblem(root, "docs/guide.md", "/docs/reference/a.md"), "");
  EXPECT_EQ(LinkProblem(root, "README.md", "docs/reference/b.md"),
            "no such file: docs/reference/b.md");
  EXPECT_EQ(LinkProblem(root, "README.md", "../shared/data/x.las"),
            "points outside the repository");
  EXPECT_EQ(LinkProblem(root, "README.md", "https://example.org/nothing"), "");
}

}  // namespace
}  // namespace candi::testing
