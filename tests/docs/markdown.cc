#include "tests/docs/markdown.h"

#include <algorithm>
#include <cctype>
#include <regex>
#include <sstream>

namespace candi::testing {

namespace {

size_t LeadingSpaces(const std::string& line) {
  size_t i = 0;
  while (i < line.size() && line[i] == ' ') ++i;
  return i;
}

// The length of the run of `c` at `pos`.
size_t RunLength(const std::string& line, size_t pos, char c) {
  size_t n = 0;
  while (pos + n < line.size() && line[pos + n] == c) ++n;
  return n;
}

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") + 1 - begin);
}

struct Fence {
  char c = 0;
  size_t length = 0;
  size_t indent = 0;
  std::string info;
};

// The opening fence on `line`, or c == 0.
Fence OpeningFence(const std::string& line) {
  Fence f;
  f.indent = LeadingSpaces(line);
  if (f.indent >= line.size() || (line[f.indent] != '`' && line[f.indent] != '~')) return f;
  const char c = line[f.indent];
  f.length = RunLength(line, f.indent, c);
  if (f.length < 3) return f;
  const std::string info = Trim(line.substr(f.indent + f.length));
  if (c == '`' && info.find('`') != std::string::npos) return f;  // inline code, not a fence
  f.c = c;
  f.info = info.substr(0, info.find_first_of(" \t{"));
  return f;
}

bool ClosesFence(const std::string& line, const Fence& open) {
  const size_t indent = LeadingSpaces(line);
  const size_t n = RunLength(line, indent, open.c);
  return n >= open.length && Trim(line.substr(indent + n)).empty();
}

// `line` with its inline code spans (`...`, ``...``) blanked out.
std::string WithoutCodeSpans(std::string line) {
  size_t i = 0;
  while ((i = line.find('`', i)) != std::string::npos) {
    const size_t n = RunLength(line, i, '`');
    size_t j = i + n;
    size_t close = std::string::npos;
    while ((j = line.find('`', j)) != std::string::npos) {
      const size_t m = RunLength(line, j, '`');
      if (m == n) {
        close = j;
        break;
      }
      j += m;
    }
    if (close == std::string::npos) {
      i += n;
      continue;
    }
    std::fill(line.begin() + static_cast<std::ptrdiff_t>(i),
              line.begin() + static_cast<std::ptrdiff_t>(close + n), ' ');
    i = close + n;
  }
  return line;
}

bool StartsWithNoCase(const std::string& s, const std::string& prefix) {
  if (s.size() < prefix.size()) return false;
  for (size_t i = 0; i < prefix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(s[i])) != prefix[i]) return false;
  }
  return true;
}

}  // namespace

MarkdownDocument ParseMarkdown(const std::string& text) {
  MarkdownDocument doc;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    doc.lines.push_back(line);
  }
  doc.in_code.assign(doc.lines.size(), false);
  Fence open;
  for (size_t i = 0; i < doc.lines.size(); ++i) {
    const std::string& l = doc.lines[i];
    if (open.c == 0) {
      open = OpeningFence(l);
      if (open.c == 0) continue;
      doc.in_code[i] = true;
      FencedBlock block;
      block.info = open.info;
      block.line = static_cast<int>(i + 1);
      doc.blocks.push_back(block);
      continue;
    }
    doc.in_code[i] = true;
    if (ClosesFence(l, open)) {
      doc.blocks.back().closed = true;
      open = Fence();
      continue;
    }
    doc.blocks.back().lines.push_back(l.substr(std::min(LeadingSpaces(l), open.indent)));
  }
  return doc;
}

std::vector<MarkdownLink> MarkdownLinks(const MarkdownDocument& doc) {
  // [text](target), ![alt](target), [text](<target with spaces>), with an optional title after.
  static const std::regex inline_link(R"(\]\(\s*(?:<([^>]*)>|([^\s)]+)))");
  // [id]: target
  static const std::regex definition(R"(^\s{0,3}\[[^\]]+\]:\s*(?:<([^>]*)>|(\S+)))");
  // <img src="..."> <a href='...'>
  static const std::regex html(R"re(\b(?:src|href)\s*=\s*(?:"([^"]*)"|'([^']*)'))re",
                               std::regex::icase);
  std::vector<MarkdownLink> links;
  for (size_t i = 0; i < doc.lines.size(); ++i) {
    if (doc.in_code[i]) continue;
    const std::string line = WithoutCodeSpans(doc.lines[i]);
    for (const std::regex* re : {&inline_link, &definition, &html}) {
      for (auto it = std::sregex_iterator(line.begin(), line.end(), *re);
           it != std::sregex_iterator(); ++it) {
        const std::smatch& m = *it;
        links.push_back({static_cast<int>(i + 1), m[1].matched ? m[1].str() : m[2].str()});
      }
    }
  }
  std::stable_sort(links.begin(), links.end(),
                   [](const MarkdownLink& a, const MarkdownLink& b) { return a.line < b.line; });
  return links;
}

std::string RelativeLinkPath(const std::string& target) {
  if (StartsWithNoCase(target, "http://") || StartsWithNoCase(target, "https://") ||
      StartsWithNoCase(target, "mailto:")) {
    return "";
  }
  const std::string path = target.substr(0, target.find_first_of("#?"));
  std::string decoded;
  for (size_t i = 0; i < path.size(); ++i) {
    if (path[i] == '%' && i + 2 < path.size() &&
        std::isxdigit(static_cast<unsigned char>(path[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(path[i + 2]))) {
      decoded += static_cast<char>(std::stoi(path.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      decoded += path[i];
    }
  }
  return decoded;
}

}  // namespace candi::testing
