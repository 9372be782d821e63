#include "io/xyz/xyz_columns.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "io/text_scan.h"

namespace candi::io::xyz {

using namespace text_scan;

constexpr const char* kColNames[] = {"x", "y", "z", "r", "g", "b", "nx", "ny", "nz"};

[[noreturn]] void BadSpec(const std::string& spec, const std::string& what) {
  throw std::invalid_argument("column spec '" + spec + "': " + what);
}

namespace {

std::string Trim(const std::string& s) {
  const size_t b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsIdentifier(const std::string& s) {
  auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  return !s.empty() && !std::isdigit(static_cast<unsigned char>(s[0])) &&
         std::all_of(s.begin(), s.end(), word);
}

// The kind of one spec entry; a scalar field's name goes to *name.
Col EntryKind(const std::string& spec, const std::string& entry, std::string* name) {
  static const std::pair<const char*, Col> kAliases[] = {
      {"x", Col::kX},    {"y", Col::kY},      {"z", Col::kZ},     {"r", Col::kR},
      {"red", Col::kR},  {"g", Col::kG},      {"green", Col::kG}, {"b", Col::kB},
      {"blue", Col::kB}, {"nx", Col::kNx},    {"ny", Col::kNy},   {"nz", Col::kNz},
      {"_", Col::kSkip}, {"skip", Col::kSkip}};
  const std::string lower = Lower(entry);
  for (const auto& [alias, kind] : kAliases) {
    if (lower == alias) return kind;
  }
  if (lower == "i" || lower == "intensity") {
    *name = "intensity";
    return Col::kScalar;
  }
  if (!IsIdentifier(entry)) {
    BadSpec(spec, "'" + entry +
                      "' is not a column name (x y z, r g b, nx ny nz, i, _ or a field "
                      "name of letters, digits and '_')");
  }
  *name = entry;
  return Col::kScalar;
}

void CheckComplete(const std::string& spec, const int (&count)[9]) {
  for (int k = 0; k < 3; ++k) {
    if (count[k] == 0)
      BadSpec(spec, std::string("no '") + kColNames[k] + "' column (x,y,z are required)");
  }
  for (int first : {3, 6}) {
    const int n = count[first] + count[first + 1] + count[first + 2];
    if (n != 0 && n != 3) {
      const std::string group = first == 3 ? "r,g,b" : "nx,ny,nz";
      BadSpec(spec, "incomplete " + group + " (all three or none)");
    }
  }
}

// Columns 4-6 hold colours when they are integers in 0..255 and not an axis-aligned unit normal
// such as "0 0 1" (which a colour almost never is: near-black).
bool LooksLikeColor(const std::vector<std::string_view>& tokens) {
  int sum_squares = 0;
  for (size_t k = 3; k < 6; ++k) {
    int v = -1;
    if (!IsNumber(tokens[k], &v) || v < 0 || v > 255) return false;
    sum_squares += v * v;
  }
  return sum_squares != 1;
}

}  // namespace

// Parses "x,y,z,r,g,b,..." (see PointReadOptions::columns). Throws std::invalid_argument naming
// the offending entry.
Layout ParseColumnSpec(const std::string& spec) {
  Layout layout;
  int count[9] = {};
  for (size_t start = 0; start <= spec.size();) {
    const size_t comma = std::min(spec.find(',', start), spec.size());
    const std::string entry = Trim(spec.substr(start, comma - start));
    start = comma + 1;
    if (entry.empty()) BadSpec(spec, "empty entry");
    std::string name;
    Column column{EntryKind(spec, entry, &name)};
    if (column.kind == Col::kScalar) {
      if (layout.schema.ScalarIndex(name) >= 0) BadSpec(spec, "'" + entry + "' appears twice");
      column.scalar = static_cast<int>(layout.schema.scalars.size());
      layout.schema.scalars.push_back({name, ScalarType::kFloat32});
    } else if (column.kind != Col::kSkip) {
      name = kColNames[static_cast<int>(column.kind)];
      if (count[static_cast<int>(column.kind)]++ > 0)
        BadSpec(spec, "'" + entry + "' appears twice");
    } else {
      name = "_";
    }
    layout.columns.push_back(column);
    layout.text += (layout.text.empty() ? "" : ",") + name;
  }
  CheckComplete(spec, count);
  layout.schema.colors = count[3] > 0;
  layout.schema.normals = count[6] > 0;
  layout.schema.position_type = ScalarType::kFloat64;
  return layout;
}

std::string GuessColumns(const std::vector<std::string_view>& tokens) {
  const size_t n = tokens.size();
  const bool color = n >= 6 && LooksLikeColor(tokens);
  if (n == 3) return "x,y,z";
  if (n == 4) return "x,y,z,i";
  if (n == 6) return color ? "x,y,z,r,g,b" : "x,y,z,nx,ny,nz";
  if (n == 7) return "x,y,z,i,r,g,b";
  if (n == 9) return color ? "x,y,z,r,g,b,nx,ny,nz" : "x,y,z,nx,ny,nz,r,g,b";
  std::string spec = "x,y,z";
  for (size_t k = 3; k < n; ++k) spec += ",c" + std::to_string(k);
  return spec;
}

// A first line is a header when a value that would be read as a number is not one (with a spec,
// skipped and extra columns may hold text).
bool IsHeader(const std::vector<std::string_view>& tokens, const Layout* layout) {
  for (size_t k = 0; k < tokens.size(); ++k) {
    if (layout && (k >= layout->columns.size() || layout->columns[k].kind == Col::kSkip)) continue;
    double v;
    if (!IsNumber(tokens[k], &v)) return true;
  }
  return false;
}

// Column names in a header line ("//X,Y,Z,R,G,B,Intensity" as CloudCompare writes it, or
// "x y z r g b" as candi does) as a layout, when they are valid names, include x, y, z, and
// match the number of values on the first point line.
std::optional<Layout> LayoutFromHeader(const std::string& header, size_t values) {
  if (header.empty()) return std::nullopt;
  const std::vector<std::string_view> names =
      SplitLine(header.data(), header.data() + header.size());
  if (names.size() != values) return std::nullopt;
  std::string spec;
  for (std::string_view name : names) spec += (spec.empty() ? "" : ",") + std::string(name);
  try {
    return ParseColumnSpec(spec);
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // not column names: an ordinary comment or title
  }
}

// The header line candi writes: the column names, so the file reads back without a spec.
std::string HeaderLine(const std::vector<Column>& columns, const PointSchema& schema) {
  std::string line = "//";
  for (size_t k = 0; k < columns.size(); ++k) {
    const Column& c = columns[k];
    line += k == 0 ? "" : " ";
    line += c.kind == Col::kScalar ? schema.scalars[c.scalar].name
            : c.kind == Col::kSkip ? "_"
                                   : kColNames[static_cast<int>(c.kind)];
  }
  return line + "\n";
}

}  // namespace candi::io::xyz
