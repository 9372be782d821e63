// The little of Markdown (CommonMark) the docs tests need: fenced code blocks and relative links.
// Used by the docs code-block runner (docs_runner.cc) and the link checker
// (tests/docs_links_test.cc).
#pragma once

#include <string>
#include <vector>

namespace candi::testing {

// A fenced code block: ``` or ~~~ (3 or more, indented by any amount, so that blocks in list items
// count), closed by a fence of the same character at least as long.
struct FencedBlock {
  std::string info;                // the info string's first word ("sh", "sh-norun", "" for none)
  int line = 0;                    // 1-based line of the opening fence
  std::vector<std::string> lines;  // the content, indentation up to the fence's removed
  bool closed = false;             // false: the document ended inside the block
};

struct MarkdownDocument {
  std::vector<std::string> lines;   // the text's lines (without "\n", "\r" removed)
  std::vector<FencedBlock> blocks;  // in document order
  std::vector<bool> in_code;        // per line: a fence or inside a fenced block
};

MarkdownDocument ParseMarkdown(const std::string& text);

// A link or image target outside code: [text](target), ![alt](target), <target> forms, reference
// definitions `[id]: target`, and HTML src="..." / href="...". Inline code spans are not links.
struct MarkdownLink {
  int line = 0;        // 1-based
  std::string target;  // as written (angle brackets and a title removed)
};
std::vector<MarkdownLink> MarkdownLinks(const MarkdownDocument& doc);

// The file part of a relative link: "" for http(s)://, mailto: and pure #anchor links; otherwise
// the target without its #anchor and ?query, %XX decoded.
std::string RelativeLinkPath(const std::string& target);

}  // namespace candi::testing
