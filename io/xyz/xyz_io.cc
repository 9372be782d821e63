#include "io/xyz/xyz_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/binary_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"
#include "io/shift_sidecar.h"
#include "io/text_scan.h"

namespace candi::io {
namespace {

using namespace text_scan;

constexpr size_t kBlockSize = size_t{4} << 20;      // bytes read from the file at a time
constexpr size_t kMaxLineLength = size_t{1} << 20;  // longer lines are an error
constexpr size_t kPtsCountWidth = 20;               // digits of the largest uint64_t

// ---------------------------------------------------------------------------------------------
// Column specs.

enum class Col : uint8_t { kX, kY, kZ, kR, kG, kB, kNx, kNy, kNz, kScalar, kSkip };
constexpr const char* kColNames[] = {"x", "y", "z", "r", "g", "b", "nx", "ny", "nz"};

struct Column {
  Col kind = Col::kSkip;
  int scalar = -1;  // kScalar: index into the schema's scalar fields
};

struct Layout {
  std::vector<Column> columns;
  PointSchema schema;  // colours, normals and float scalar fields, as the columns say
  std::string text;    // canonical spec, e.g. "x,y,z,r,g,b", for messages
};

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

[[noreturn]] void BadSpec(const std::string& spec, const std::string& what) {
  throw std::invalid_argument("column spec '" + spec + "': " + what);
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

inline uint8_t& Channel(Rgb8& rgb, Col kind) {
  return kind == Col::kR ? rgb.r : kind == Col::kG ? rgb.g : rgb.b;
}
inline uint8_t Channel(const Rgb8& rgb, Col kind) { return Channel(const_cast<Rgb8&>(rgb), kind); }

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
  const std::vector<std::string_view> names = SplitLine(header.data(), header.data() + header.size());
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
            : c.kind == Col::kSkip ? "_" : kColNames[static_cast<int>(c.kind)];
  }
  return line + "\n";
}

// ---------------------------------------------------------------------------------------------
// Reader.

// Where one line's values go.
struct PointSlot {
  double* position;
  Rgb8* color;    // null without colours
  float* normal;  // null without normals
  PointCloud* chunk;
  size_t n;  // index of the point in chunk
};

class XyzReader : public PointReader {
 public:
  XyzReader(const std::string& path, bool pts, std::optional<Layout> layout, bool scalar_fields);
  size_t Read(size_t max_points, PointCloud* chunk) override;

 private:
  bool NextLine(const char** begin, const char** end);
  bool NextDataLine(const char** begin, const char** end);
  void Refill();
  void ReadPtsCount(const char* begin, const char* end);
  std::vector<std::string_view> FirstPointLine(const Layout* layout, const char** begin,
                                               const char** end);
  void ChooseLayout(std::optional<Layout> layout, const std::vector<std::string_view>& tokens);
  bool ParseLine(const char* p, const char* end, size_t n, PointCloud* chunk);
  const char* ParseValue(const Column& c, const char* p, const char* end, size_t k,
                         const PointSlot& slot);
  bool ShortLine(const char* begin, const char* end);
  void Finish();
  [[noreturn]] void Fail(const std::string& message) const;
  [[noreturn]] void Fail(size_t column, const char* p, const char* end,
                         const std::string& what) const;

  BinaryFile file_;
  bool pts_;
  Layout layout_;
  std::vector<char> buffer_;
  size_t begin_ = 0, end_ = 0;  // unread bytes of buffer_
  bool eof_ = false;
  uint64_t lines_ = 0;                 // lines taken from the buffer
  uint64_t line_ = 0;                  // number of the line being parsed (1-based)
  std::string pending_;                // the first point line, read while opening
  std::string header_;                 // column names from a header or comment line, if any
  uint64_t header_line_ = 0;
  uint64_t pending_line_ = 0;          // its number, 0 when there is none
  uint64_t declared_ = kUnknownCount;  // PTS: the count line(s)
  bool warned_extra_ = false, warned_sections_ = false, finished_ = false;
};

XyzReader::XyzReader(const std::string& path, bool pts, std::optional<Layout> layout,
                     bool scalar_fields)
    : PointReader(path), file_(path), pts_(pts), buffer_(std::min<uint64_t>(kBlockSize + kMaxLineLength, file_.size()) + 2) {
  if (file_.size() == 0) throw InputError(path, "byte 0", "empty file");
  info_.format = pts ? PointFormat::kPts : PointFormat::kXyz;
  if (std::optional<LocalFrame> frame = ReadShiftSidecar(path)) info_.frame = *frame;
  const char *b = nullptr, *e = nullptr;
  const std::vector<std::string_view> tokens = FirstPointLine(layout ? &*layout : nullptr, &b, &e);
  if (!tokens.empty()) {
    pending_.assign(b, e);
    pending_line_ = line_;
  }
  ChooseLayout(std::move(layout), tokens);
  if (!scalar_fields) {  // PointReadOptions::scalar_fields: geometry and colour only
    for (Column& c : layout_.columns) {
      if (c.kind == Col::kScalar) c = Column{Col::kSkip, -1};
    }
    layout_.schema.scalars.clear();
  }
  info_.count = declared_;
  info_.schema = layout_.schema;
  info_.description = PointFormatName(info_.format) + " text, columns " + layout_.text;
}

// Finds the first line of points: skips comments, the PTS count line and an XYZ header line.
// Returns its values (none when the file has no points).
std::vector<std::string_view> XyzReader::FirstPointLine(const Layout* layout, const char** b,
                                                        const char** e) {
  if (!NextDataLine(b, e)) return {};
  if (pts_) {
    ReadPtsCount(*b, *e);
    if (declared_ != kUnknownCount && !NextDataLine(b, e)) return {};
  }
  std::vector<std::string_view> tokens = SplitLine(*b, *e);
  if (!pts_ && IsHeader(tokens, layout)) {
    LogInfo(path_ + ": line " + std::to_string(line_) + " is not numeric; skipped as a header: '" +
            std::string(*b, std::min<size_t>(*e - *b, 200)) + "'");
    header_.assign(*b, *e);
    header_line_ = line_;
    if (!NextDataLine(b, e)) return {};
    tokens = SplitLine(*b, *e);
  }
  if (std::memchr(*b, ',', *e - *b) != nullptr && std::memchr(*b, ';', *e - *b) != nullptr) {
    Fail("mixes ',' and ';' separators; decimal commas are not supported (use '.')");
  }
  return tokens;
}

void XyzReader::ReadPtsCount(const char* b, const char* e) {
  const std::vector<std::string_view> tokens = SplitLine(b, e);
  uint64_t count = 0;
  if (tokens.size() == 1 && IsNumber(tokens[0], &count)) {
    declared_ = count;
  } else if (tokens.size() == 1) {
    Fail("expected the PTS point count, found '" + std::string(tokens[0]) + "'");
  } else {
    LogWarning(path_ + ": line " + std::to_string(line_) +
               ": no PTS point-count line; reading the points directly");
  }
}

void XyzReader::ChooseLayout(std::optional<Layout> layout,
                             const std::vector<std::string_view>& tokens) {
  if (layout) {
    layout_ = std::move(*layout);
  } else if (tokens.empty()) {
    layout_ = ParseColumnSpec(pts_ ? "x,y,z,i" : "x,y,z");
    LogInfo(path_ + ": no points");
  } else {
    if (tokens.size() < 3) {
      Fail(std::to_string(tokens.size()) + " column(s); at least x,y,z are needed");
    }
    if (std::optional<Layout> named = LayoutFromHeader(header_, tokens.size())) {
      layout_ = std::move(*named);
      LogInfo(path_ + ": columns " + layout_.text + " from the header on line " +
              std::to_string(header_line_));
      return;
    }
    layout_ = ParseColumnSpec(GuessColumns(tokens));
    LogInfo(path_ + ": " + std::to_string(tokens.size()) + " columns, guessed " + layout_.text +
            "; pass --columns to override");
  }
}

void XyzReader::Refill() {
  const size_t left = end_ - begin_;
  std::memmove(buffer_.data(), buffer_.data() + begin_, left);
  begin_ = 0;
  end_ = left;
  const size_t want = buffer_.size() - 1 - left;
  const size_t got = file_.ReadSome(buffer_.data() + left, want);
  end_ += got;
  buffer_[end_] = '\n';  // the sentinel after a last line without '\n'
  eof_ = got < want;
}

// The next line (without '\n'), from the block buffer; false at the end of the file.
bool XyzReader::NextLine(const char** begin, const char** end) {
  while (true) {
    const char* start = buffer_.data() + begin_;
    const void* nl = std::memchr(start, '\n', end_ - begin_);
    const char* stop = nl ? static_cast<const char*>(nl) : buffer_.data() + end_;
    if (static_cast<size_t>(stop - start) > kMaxLineLength) {
      line_ = lines_ + 1;
      Fail("line longer than " + std::to_string(kMaxLineLength) + " bytes");
    }
    if (nl != nullptr || (eof_ && begin_ != end_)) {
      *begin = start;
      *end = stop;
      begin_ = std::min<size_t>(stop - buffer_.data() + 1, end_);
      ++lines_;
      return true;
    }
    if (eof_) return false;
    Refill();
  }
}

// The next line that is neither empty nor a comment ('#' or '//').
bool XyzReader::NextDataLine(const char** begin, const char** end) {
  if (pending_line_ != 0) {
    *begin = pending_.data();
    *end = pending_.data() + pending_.size();
    line_ = pending_line_;
    pending_line_ = 0;
    return true;
  }
  while (NextLine(begin, end)) {
    const char* p = SkipBlanks(*begin);
    if (p == *end) continue;
    if (*p == '#' || (*p == '/' && p + 1 != *end && p[1] == '/')) {
      // Before the first point, a comment may name the columns ("//x y z r g b intensity").
      if (points_read_ == 0 && pending_.empty()) {
        header_.assign(p + (*p == '#' ? 1 : 2), *end);
        header_line_ = lines_;
      }
      continue;
    }
    line_ = lines_;
    return true;
  }
  return false;
}

size_t XyzReader::Read(size_t max_points, PointCloud* chunk) {
  CANDI_CHECK(max_points > 0) << "Read: max_points must be > 0";
  PrepareChunk(chunk);
  chunk->Clear();
  size_t n = 0;
  const char *b = nullptr, *e = nullptr;
  while (n < max_points && NextDataLine(&b, &e)) {
    if (n == chunk->size()) chunk->Resize(std::min(max_points, std::max<size_t>(4096, 2 * n)));
    if (ParseLine(b, e, n, chunk)) ++n;
  }
  chunk->Resize(n);
  points_read_ += n;
  if (n == 0) Finish();
  return n;
}

void XyzReader::Finish() {
  if (finished_) return;
  finished_ = true;
  if (declared_ != kUnknownCount && declared_ != points_read_) {
    LogWarning(path_ + ": the PTS count line says " + std::to_string(declared_) +
               " points, the file has " + std::to_string(points_read_));
  }
  info_.count = points_read_;
}

// Parses one line into point n of *chunk. False when the line is not a point (a PTS section's
// count line).
bool XyzReader::ParseLine(const char* p, const char* end, size_t n, PointCloud* chunk) {
  const PointSlot slot{chunk->positions[n].data(),
                       layout_.schema.colors ? &chunk->colors[n] : nullptr,
                       layout_.schema.normals ? chunk->normals[n].data() : nullptr, chunk, n};
  const char* line = p;
  p = SkipBlanks(p);
  const size_t columns = layout_.columns.size();
  for (size_t k = 0; k < columns; ++k) {
    if (p == end) return ShortLine(line, end);
    if (IsComma(*p)) Fail(k, p, end, "empty value");
    p = NextValue(ParseValue(layout_.columns[k], p, end, k, slot));
  }
  if (p != end && !warned_extra_) {
    warned_extra_ = true;
    LogWarning(path_ + ": line " + std::to_string(line_) + " has " +
               std::to_string(SplitLine(line, end).size()) + " columns, the spec " + layout_.text +
               " has " + std::to_string(columns) + "; extra columns ignored (not logged again)");
  }
  return true;
}

inline const char* XyzReader::ParseValue(const Column& c, const char* p, const char* end, size_t k,
                                         const PointSlot& slot) {
  const char* q = nullptr;
  switch (c.kind) {
    case Col::kX:
    case Col::kY:
    case Col::kZ: {
      double& v = slot.position[static_cast<int>(c.kind)];
      q = ParseNumber(p, end, &v);
      if (q != nullptr && !std::isfinite(v)) Fail(k, p, end, "coordinate is not finite");
      break;
    }
    case Col::kR:
    case Col::kG:
    case Col::kB: {
      int v = -1;
      q = ParseNumber(p, end, &v);
      if (q == nullptr || v < 0 || v > 255) Fail(k, p, end, "colour is not an integer in 0..255");
      Channel(*slot.color, c.kind) = static_cast<uint8_t>(v);
      break;
    }
    case Col::kNx:
    case Col::kNy:
    case Col::kNz:
      q = ParseNumber(p, end, &slot.normal[static_cast<int>(c.kind) - 6]);
      break;
    case Col::kScalar:
      q = ParseNumber(p, end, &slot.chunk->scalars[c.scalar].f32[slot.n]);
      break;
    case Col::kSkip:
      for (q = p; q != end && !IsSeparator(*q);) ++q;
      break;
  }
  if (q == nullptr) Fail(k, p, end, "not a number");
  return q;
}

// A line with fewer values than the spec: an error, except a PTS section's count line.
bool XyzReader::ShortLine(const char* begin, const char* end) {
  const std::vector<std::string_view> tokens = SplitLine(begin, end);
  uint64_t count = 0;
  if (pts_ && tokens.size() == 1 && IsNumber(tokens[0], &count)) {
    if (!warned_sections_)
      LogInfo(path_ + ": line " + std::to_string(line_) + ": a new PTS section");
    warned_sections_ = true;
    declared_ = (declared_ == kUnknownCount ? 0 : declared_) + count;
    return false;
  }
  Fail("expected " + std::to_string(layout_.columns.size()) + " columns (" + layout_.text +
       "), found " + std::to_string(tokens.size()));
}

void XyzReader::Fail(const std::string& message) const {
  throw InputError(path_, "line " + std::to_string(line_), message);
}

void XyzReader::Fail(size_t column, const char* p, const char* end, const std::string& what) const {
  const char* q = p;
  while (q != end && !IsSeparator(*q) && q - p < 40) ++q;
  throw InputError(path_,
                   "line " + std::to_string(line_) + ", column " + std::to_string(column + 1),
                   what + ": '" + std::string(p, q) + "'");
}

// ---------------------------------------------------------------------------------------------
// Writer.

// The columns written for `spec`: options.columns, or x,y,z,[intensity],[r,g,b],[nx,ny,nz],
// [other scalars]. Intensity comes first so that x,y,z,i,r,g,b files read back with the guess.
std::vector<Column> WriterColumns(const PointWriteSpec& spec, const PointWriteOptions& options) {
  const PointSchema& schema = spec.schema;
  std::string text = options.columns;
  if (text.empty()) {
    const int intensity = schema.ScalarIndex("intensity");
    text = "x,y,z";
    if (intensity >= 0) text += ",intensity";
    if (schema.colors) text += ",r,g,b";
    if (schema.normals) text += ",nx,ny,nz";
    for (int k = 0; k < static_cast<int>(schema.scalars.size()); ++k) {
      if (k != intensity) text += "," + schema.scalars[k].name;
    }
  }
  Layout layout = ParseColumnSpec(text);
  if (layout.schema.colors && !schema.colors) BadSpec(text, "r,g,b but the points have no colours");
  if (layout.schema.normals && !schema.normals)
    BadSpec(text, "nx,ny,nz but the points have no normals");
  for (Column& c : layout.columns) {
    if (c.kind == Col::kSkip) BadSpec(text, "'_' (skip) cannot be written");
    if (c.kind != Col::kScalar) continue;
    const std::string& name = layout.schema.scalars[c.scalar].name;
    c.scalar = schema.ScalarIndex(name);
    if (c.scalar < 0) BadSpec(text, "the points have no scalar field '" + name + "'");
  }
  return layout.columns;
}

bool WriteFloatPositions(const PointWriteSpec& spec, const PointWriteOptions& options) {
  if (options.precision != PositionPrecision::kAuto) {
    return options.precision == PositionPrecision::kFloat32;
  }
  return spec.frame.IsIdentity() && spec.schema.position_type == ScalarType::kFloat32;
}

inline char* AppendByte(char* out, uint8_t v) {
  if (v >= 100) *out++ = static_cast<char>('0' + v / 100);
  if (v >= 10) *out++ = static_cast<char>('0' + v / 10 % 10);
  *out++ = static_cast<char>('0' + v % 10);
  return out;
}

class XyzWriter : public PointWriter {
 public:
  XyzWriter(const std::string& path, bool pts, const PointWriteSpec& spec,
            std::vector<Column> columns, bool float_positions);
  void Write(const PointCloud& chunk) override;
  void Close() override;

 private:
  char* AppendPoint(char* out, const PointCloud& chunk, size_t i, const Eigen::Vector3d& p) const;
  void Flush();

  std::string path_;
  bool pts_;
  PointWriteSpec spec_;
  std::vector<Column> columns_;
  bool float_positions_;
  size_t max_line_;  // bytes of the longest possible line
  AtomicFile file_;
  std::vector<char> buffer_;
  size_t used_ = 0;
  bool closed_ = false;
};

XyzWriter::XyzWriter(const std::string& path, bool pts, const PointWriteSpec& spec,
                     std::vector<Column> columns, bool float_positions)
    : path_(path),
      pts_(pts),
      spec_(spec),
      columns_(std::move(columns)),
      float_positions_(float_positions),
      max_line_(33 * columns_.size() + 1),
      file_(path),
      buffer_(kBlockSize + max_line_) {
  if (spec.schema.alphas || spec.schema.layers) {
    LogInfo(path + ": alphas and layers are not written to " + (pts ? "PTS" : "XYZ"));
  }
  if (pts_) {
    // An unknown count gets a blank field, patched in Close(); trailing blanks parse fine.
    const std::string count =
        spec.count == kUnknownCount ? std::string(kPtsCountWidth, ' ') : std::to_string(spec.count);
    file_.Write(count + "\n");
  } else {
    file_.Write(HeaderLine(columns_, spec.schema));
  }
}

void XyzWriter::Write(const PointCloud& chunk) {
  CANDI_CHECK(!closed_) << "XyzWriter::Write after Close";
  CANDI_CHECK(chunk.schema == spec_.schema) << path_ << ": chunk schema differs from the spec";
  chunk.CheckConsistent();
  const bool same_frame = chunk.frame == spec_.frame;
  for (size_t i = 0; i < chunk.size(); ++i) {
    if (used_ + max_line_ > buffer_.size()) Flush();
    const Eigen::Vector3d p =
        same_frame
            ? chunk.positions[i]
            : Eigen::Vector3d((chunk.positions[i] + chunk.frame.origin) - spec_.frame.origin);
    used_ = AppendPoint(buffer_.data() + used_, chunk, i, p) - buffer_.data();
  }
  points_written_ += chunk.size();
}

char* XyzWriter::AppendPoint(char* out, const PointCloud& chunk, size_t i,
                             const Eigen::Vector3d& p) const {
  for (size_t k = 0; k < columns_.size(); ++k) {
    if (k > 0) *out++ = ' ';
    const Column& c = columns_[k];
    const int axis = static_cast<int>(c.kind);
    switch (c.kind) {
      case Col::kX:
      case Col::kY:
      case Col::kZ:
        out = float_positions_ ? AppendFloat(out, static_cast<float>(p[axis]))
                               : AppendDouble(out, p[axis]);
        break;
      case Col::kR:
      case Col::kG:
      case Col::kB:
        out = AppendByte(out, Channel(chunk.colors[i], c.kind));
        break;
      case Col::kNx:
      case Col::kNy:
      case Col::kNz:
        out = AppendFloat(out, chunk.normals[i][axis - 6]);
        break;
      case Col::kScalar: {
        const ScalarField& f = chunk.scalars[c.scalar];
        out = f.spec.type == ScalarType::kFloat32 ? AppendFloat(out, f.f32[i])
                                                  : AppendDouble(out, f.f64[i]);
        break;
      }
      case Col::kSkip:
        break;
    }
  }
  *out++ = '\n';
  return out;
}

void XyzWriter::Flush() {
  file_.Write(buffer_.data(), used_);
  used_ = 0;
}

void XyzWriter::Close() {
  CANDI_CHECK(!closed_) << "XyzWriter::Close twice";
  Flush();
  if (pts_ && spec_.count == kUnknownCount) {
    const std::string count = std::to_string(points_written_);
    file_.WriteAt(0, count.data(), count.size());
  } else if (pts_) {
    CANDI_CHECK_EQ(points_written_, spec_.count) << path_ << ": PTS count line";
  }
  file_.Commit();
  closed_ = true;
  if (!spec_.frame.IsIdentity()) {
    WriteShiftSidecar(path_, spec_.frame);
  } else {
    std::remove(ShiftSidecarPath(path_).c_str());  // a stale sidecar would shift the new file
  }
}

}  // namespace

std::unique_ptr<PointReader> OpenXyzReader(const std::string& path, bool pts,
                                           const PointReadOptions& options) {
  std::optional<Layout> layout;
  if (!options.columns.empty()) layout = ParseColumnSpec(options.columns);
  return std::make_unique<XyzReader>(path, pts, std::move(layout), options.scalar_fields);
}

std::unique_ptr<PointWriter> OpenXyzWriter(const std::string& path, bool pts,
                                           const PointWriteSpec& spec,
                                           const PointWriteOptions& options) {
  std::vector<Column> columns = WriterColumns(spec, options);
  return std::make_unique<XyzWriter>(path, pts, spec, std::move(columns),
                                     WriteFloatPositions(spec, options));
}

}  // namespace candi::io
