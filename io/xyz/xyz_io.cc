#include "io/xyz/xyz_io.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <set>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "core/atomic_file.h"
#include "core/mapped_file.h"
#include "core/parallel.h"
#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"
#include "io/shift_sidecar.h"
#include "io/text_scan.h"
#include "io/xyz/xyz_columns.h"

namespace candi::io {
namespace {

// A file's column layout is a fact of the file: said once per process, however often a command
// opens it (`candi render FILE` opens it to decide how to render, to peek at its schema, then to
// read it).
void LogLayoutOnce(const std::string& message) {
  static std::mutex mutex;
  static std::set<std::string> said;
  std::lock_guard<std::mutex> lock(mutex);
  if (said.insert(message).second) LogInfo(message);
}

using namespace text_scan;
using namespace xyz;

constexpr size_t kBlockSize = size_t{4} << 20;      // bytes the writer buffers
constexpr size_t kMaxLineLength = size_t{1} << 20;  // longer lines are an error
constexpr size_t kPtsCountWidth = 20;               // digits of the largest uint64_t
constexpr uint64_t kTextBlock = uint64_t{1} << 20;  // text a thread parses at a time, about
constexpr uint64_t kRegion = uint64_t{64} << 20;    // text one pass over the blocks covers, at most

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

// What parsing a run of lines saw that the reader reports once, in file order.
struct LineNotes {
  uint64_t line = 0;            // the number of the line being parsed
  uint64_t extra_line = 0;      // the first line with more values than the spec (0: none)
  size_t extra_values = 0;      // its number of values
  uint64_t section_line = 0;    // the first PTS section count line (0: none)
  uint64_t section_points = 0;  // the sum of the section counts
};

// A run of lines parsed on its own (a block of the text, or the first point line).
struct TextBlock {
  PointCloud points;
  uint64_t first_line = 0;  // the number given to the line before the run
  uint64_t lines = 0;       // lines consumed
  size_t bytes = 0;         // bytes consumed
  LineNotes notes;
  bool failed = false;  // a line after the consumed ones is bad
};

class XyzReader : public PointReader {
 public:
  XyzReader(const std::string& path, bool pts, std::optional<Layout> layout, bool scalar_fields);
  size_t Read(size_t max_points, PointCloud* chunk) override;

 private:
  bool NextLine(const char** begin, const char** end);
  bool NextDataLine(const char** begin, const char** end);
  void ReadPtsCount(const char* begin, const char* end);
  std::vector<std::string_view> FirstPointLine(const Layout* layout, const char** begin,
                                               const char** end);
  void ChooseLayout(std::optional<Layout> layout, const std::vector<std::string_view>& tokens);
  size_t ReadRegion(size_t max_points, PointCloud* chunk);
  std::vector<uint64_t> CutBlocks(uint64_t bytes) const;
  void ParseBlock(const char* begin, const char* end, size_t limit, uint64_t first_line,
                  TextBlock* out) const;
  size_t Take(TextBlock* block, uint64_t base_line, PointCloud* chunk);
  void Report(const LineNotes& notes, uint64_t shift);
  bool ParseLine(const char* p, const char* end, size_t n, PointCloud* chunk,
                 LineNotes* notes) const;
  const char* ParseValue(const Column& c, const char* p, const char* end, size_t k,
                         const PointSlot& slot, const LineNotes& notes) const;
  bool ShortLine(const char* begin, const char* end, LineNotes* notes) const;
  void Finish();
  [[noreturn]] void Fail(uint64_t line, const std::string& message) const;
  [[noreturn]] void Fail(uint64_t line, size_t column, const char* p, const char* end,
                         const std::string& what) const;

  MappedFile map_;
  const char* text_;  // map_'s bytes
  bool pts_;
  Layout layout_;
  uint64_t pos_ = 0;         // the first unread byte
  uint64_t first_data_ = 0;  // the byte after the first point line
  std::string last_line_;    // the last line when it lacks '\n' (a sentinel follows)
  uint64_t lines_ = 0;       // lines consumed
  uint64_t line_ = 0;        // opening: the number of the line being parsed
  std::string pending_;      // the first point line, read while opening
  std::string header_;       // column names from a header or comment line, if any
  uint64_t header_line_ = 0;
  uint64_t pending_line_ = 0;          // its number, 0 when there is none
  uint64_t declared_ = kUnknownCount;  // PTS: the count line(s)
  bool warned_extra_ = false, warned_sections_ = false, finished_ = false;
};

XyzReader::XyzReader(const std::string& path, bool pts, std::optional<Layout> layout,
                     bool scalar_fields)
    : PointReader(path), map_(path), text_(reinterpret_cast<const char*>(map_.data())), pts_(pts) {
  if (map_.size() == 0) throw InputError(path, "byte 0", "empty file");
  info_.format = pts ? PointFormat::kPts : PointFormat::kXyz;
  if (std::optional<LocalFrame> frame = ReadShiftSidecar(path)) info_.frame = *frame;
  const char *b = nullptr, *e = nullptr;
  const std::vector<std::string_view> tokens = FirstPointLine(layout ? &*layout : nullptr, &b, &e);
  if (!tokens.empty()) {
    pending_.assign(b, e);
    pending_line_ = line_;
  }
  first_data_ = pos_;
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
    Fail(line_, "mixes ',' and ';' separators; decimal commas are not supported (use '.')");
  }
  return tokens;
}
void XyzReader::ReadPtsCount(const char* b, const char* e) {
  const std::vector<std::string_view> tokens = SplitLine(b, e);
  uint64_t count = 0;
  if (tokens.size() == 1 && IsNumber(tokens[0], &count)) {
    declared_ = count;
  } else if (tokens.size() == 1) {
    Fail(line_, "expected the PTS point count, found '" + std::string(tokens[0]) + "'");
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
    LogLayoutOnce(path_ + ": no points");
  } else {
    if (tokens.size() < 3) {
      Fail(line_, std::to_string(tokens.size()) + " column(s); at least x,y,z are needed");
    }
    if (std::optional<Layout> named = LayoutFromHeader(header_, tokens.size())) {
      layout_ = std::move(*named);
      LogLayoutOnce(path_ + ": columns " + layout_.text + " from the header on line " +
                    std::to_string(header_line_));
      return;
    }
    layout_ = ParseColumnSpec(GuessColumns(tokens));
    LogLayoutOnce(path_ + ": " + std::to_string(tokens.size()) + " columns, guessed " + layout_.text +
                  "; pass --columns to override");
  }
}

// Opening: the next line (without '\n'); false at the end of the file.
bool XyzReader::NextLine(const char** begin, const char** end) {
  const uint64_t size = map_.size();
  if (pos_ >= size) return false;
  const char* start = text_ + pos_;
  const void* nl = std::memchr(start, '\n', size - pos_);
  const char* stop = nl ? static_cast<const char*>(nl) : text_ + size;
  if (static_cast<size_t>(stop - start) > kMaxLineLength) {
    Fail(lines_ + 1, "line longer than " + std::to_string(kMaxLineLength) + " bytes");
  }
  ++lines_;
  pos_ = nl ? stop - text_ + 1 : size;
  if (nl == nullptr) {  // the parsers need a sentinel after the line: a copy ends with '\0'
    last_line_.assign(start, stop);
    start = last_line_.data();
    stop = start + last_line_.size();
  }
  *begin = start;
  *end = stop;
  return true;
}

// Opening: the next line that is neither empty nor a comment ('#' or '//').
bool XyzReader::NextDataLine(const char** begin, const char** end) {
  while (NextLine(begin, end)) {
    const char* p = SkipBlanks(*begin);
    if (p == *end) continue;
    if (*p == '#' || (*p == '/' && p + 1 != *end && p[1] == '/')) {
      // Before the first point, a comment may name the columns ("//x y z r g b intensity").
      header_.assign(p + (*p == '#' ? 1 : 2), *end);
      header_line_ = lines_;
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
  if (pending_line_ != 0) {  // the first point line, read while opening
    TextBlock first;
    ParseBlock(pending_.data(), pending_.data() + pending_.size(), 1, pending_line_ - 1, &first);
    n += Take(&first, pending_line_ - 1, chunk);
    pending_line_ = 0;
  }
  while (n < max_points && pos_ < map_.size()) n += ReadRegion(max_points - n, chunk);
  points_read_ += n;
  if (n == 0) Finish();
  return n;
}

// Parses the text from pos_ in blocks, in parallel, and appends up to max_points points to
// *chunk in file order. Each block starts at a line and is parsed on its own; what the blocks
// saw is then taken in order, so points, errors (the first bad line) and notes are those of a
// reading line by line, whatever the number of threads.
size_t XyzReader::ReadRegion(size_t max_points, PointCloud* chunk) {
  const uint64_t read = points_read_ + chunk->size();  // the points after first_data_, about
  const uint64_t points = read > 0 && !pending_.empty() ? read - 1 : read;
  const double per_point = points > 0 && pos_ > first_data_
                               ? static_cast<double>(pos_ - first_data_) / points
                               : static_cast<double>(pending_.size() + 1);
  const double want = std::min<double>(kRegion, 1.0625 * per_point * max_points + 4096);
  map_.CheckSize(map_.size(), "the text");  // a file cut since opening: an error, not SIGBUS
  const std::vector<uint64_t> cuts = CutBlocks(static_cast<uint64_t>(want));
  map_.WillNeed(cuts.back(), cuts.back() - pos_);  // the next region, read while this one parses
  std::vector<TextBlock> blocks(cuts.size() - 1);
  ParallelFor(size_t{0}, blocks.size(), [&](size_t b) {
    try {  // the line numbers are not known yet: a bad block is parsed again in order
      ParseBlock(text_ + cuts[b], text_ + cuts[b + 1], max_points, 0, &blocks[b]);
    } catch (const InputError&) {
      blocks[b].failed = true;
    }
  });
  size_t n = 0;
  for (size_t b = 0; b < blocks.size() && n < max_points; ++b) {
    TextBlock& block = blocks[b];
    const size_t need = max_points - n;
    if (block.points.size() > need || (block.failed && block.points.size() < need)) {
      // Too many points (keep the first `need`), or an error to raise with its line number.
      block = TextBlock();
      try {
        ParseBlock(text_ + cuts[b], text_ + cuts[b + 1], need, lines_, &block);
      } catch (const InputError&) {
        Report(block.notes, 0);  // what the lines before the bad one would have logged
        throw;
      }
    }
    pos_ += block.bytes;
    const uint64_t base_line = lines_;
    lines_ += block.lines;
    n += Take(&block, base_line, chunk);
  }
  return n;
}

// Block boundaries from pos_ covering about `bytes`: blocks of about kTextBlock, each ending
// after a '\n' (the end of the line holding its nominal last byte) or at the end of the file. A
// line too long to find the end of ends its block early; parsing reports it.
std::vector<uint64_t> XyzReader::CutBlocks(uint64_t bytes) const {
  const uint64_t size = map_.size(), stop = std::min(size, pos_ + std::max<uint64_t>(bytes, 1));
  std::vector<uint64_t> cuts{pos_};
  while (cuts.back() < stop) {
    const uint64_t at = std::min(stop, cuts.back() + kTextBlock) - 1;  // nominal last byte
    const uint64_t window = std::min<uint64_t>(size - at, kMaxLineLength + 2);
    const void* nl = std::memchr(text_ + at, '\n', window);
    cuts.push_back(nl ? static_cast<const char*>(nl) - text_ + 1 : at + window);
  }
  return cuts;
}

// Parses the lines of [begin, end) into out->points until `limit` points; the first line is
// numbered first_line + 1. Throws InputError at a bad line (out then holds what came before).
void XyzReader::ParseBlock(const char* begin, const char* end, size_t limit, uint64_t first_line,
                           TextBlock* out) const {
  PointCloud& cloud = out->points;
  cloud.SetSchema(info_.schema);
  cloud.frame = info_.frame;
  out->first_line = first_line;
  LineNotes& notes = out->notes;
  notes.line = first_line;
  std::string last;  // a last line without '\n', copied for the sentinel after it
  size_t n = 0;
  for (const char* p = begin; n < limit && p < end;) {
    const void* nl = std::memchr(p, '\n', end - p);
    const char *b = p, *e = nl ? static_cast<const char*>(nl) : end;
    ++notes.line;
    if (static_cast<size_t>(e - b) > kMaxLineLength) {
      cloud.Resize(n);
      Fail(notes.line, "line longer than " + std::to_string(kMaxLineLength) + " bytes");
    }
    p = nl ? e + 1 : end;
    if (nl == nullptr) {
      last.assign(b, e);
      b = last.data();
      e = b + last.size();
    }
    const char* q = SkipBlanks(b);
    if (q != e && *q != '#' && !(*q == '/' && q + 1 != e && q[1] == '/')) {
      if (n == cloud.size()) cloud.Resize(std::min(limit, std::max<size_t>(4096, 2 * n)));
      try {
        n += ParseLine(b, e, n, &cloud, &notes);
      } catch (const InputError&) {
        cloud.Resize(n);
        throw;
      }
    }
    out->lines = notes.line - first_line;
    out->bytes = static_cast<size_t>(p - begin);
  }
  cloud.Resize(n);
}

// Appends a parsed block to *chunk and reports what it saw (its lines renumbered to follow
// base_line). Returns its number of points.
size_t XyzReader::Take(TextBlock* block, uint64_t base_line, PointCloud* chunk) {
  Report(block->notes, base_line - block->first_line);  // modulo 2^64
  chunk->Append(block->points);
  return block->points.size();
}

// Logs what a reading line by line would have logged at these lines (numbered + shift), once,
// in line order.
void XyzReader::Report(const LineNotes& s, uint64_t shift) {
  auto extra = [&] {
    if (s.extra_line == 0 || warned_extra_) return;
    warned_extra_ = true;
    LogWarning(path_ + ": line " + std::to_string(s.extra_line + shift) + " has " +
               std::to_string(s.extra_values) + " columns, the spec " + layout_.text + " has " +
               std::to_string(layout_.columns.size()) +
               "; extra columns ignored (not logged again)");
  };
  auto section = [&] {
    if (s.section_line == 0) return;
    if (!warned_sections_) {
      LogInfo(path_ + ": line " + std::to_string(s.section_line + shift) + ": a new PTS section");
    }
    warned_sections_ = true;
    declared_ = (declared_ == kUnknownCount ? 0 : declared_) + s.section_points;
  };
  if (s.extra_line != 0 && (s.section_line == 0 || s.extra_line < s.section_line)) {
    extra();
    section();
  } else {
    section();
    extra();
  }
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
// count line). Thread-safe: what is to be logged goes to *notes.
bool XyzReader::ParseLine(const char* p, const char* end, size_t n, PointCloud* chunk,
                          LineNotes* notes) const {
  const PointSlot slot{chunk->positions[n].data(),
                       layout_.schema.colors ? &chunk->colors[n] : nullptr,
                       layout_.schema.normals ? chunk->normals[n].data() : nullptr, chunk, n};
  const char* line = p;
  p = SkipBlanks(p);
  const size_t columns = layout_.columns.size();
  for (size_t k = 0; k < columns; ++k) {
    if (p == end) return ShortLine(line, end, notes);
    if (IsComma(*p)) Fail(notes->line, k, p, end, "empty value");
    p = NextValue(ParseValue(layout_.columns[k], p, end, k, slot, *notes));
  }
  if (p != end && notes->extra_line == 0) {
    notes->extra_line = notes->line;
    notes->extra_values = SplitLine(line, end).size();
  }
  return true;
}

inline const char* XyzReader::ParseValue(const Column& c, const char* p, const char* end, size_t k,
                                         const PointSlot& slot, const LineNotes& notes) const {
  const char* q = nullptr;
  switch (c.kind) {
    case Col::kX:
    case Col::kY:
    case Col::kZ: {
      double& v = slot.position[static_cast<int>(c.kind)];
      q = ParseNumber(p, end, &v);
      if (q != nullptr && !std::isfinite(v))
        Fail(notes.line, k, p, end, "coordinate is not finite");
      break;
    }
    case Col::kR:
    case Col::kG:
    case Col::kB: {
      int v = -1;
      q = ParseNumber(p, end, &v);
      if (q == nullptr || v < 0 || v > 255)
        Fail(notes.line, k, p, end, "colour is not an integer in 0..255");
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
  if (q == nullptr) Fail(notes.line, k, p, end, "not a number");
  return q;
}

// A line with fewer values than the spec: an error, except a PTS section's count line.
bool XyzReader::ShortLine(const char* begin, const char* end, LineNotes* notes) const {
  const std::vector<std::string_view> tokens = SplitLine(begin, end);
  uint64_t count = 0;
  if (pts_ && tokens.size() == 1 && IsNumber(tokens[0], &count)) {
    if (notes->section_line == 0) notes->section_line = notes->line;
    notes->section_points += count;
    return false;
  }
  Fail(notes->line, "expected " + std::to_string(layout_.columns.size()) + " columns (" +
                        layout_.text + "), found " + std::to_string(tokens.size()));
}

void XyzReader::Fail(uint64_t line, const std::string& message) const {
  throw InputError(path_, "line " + std::to_string(line), message);
}

void XyzReader::Fail(uint64_t line, size_t column, const char* p, const char* end,
                     const std::string& what) const {
  const char* q = p;
  while (q != end && !IsSeparator(*q) && q - p < 40) ++q;
  throw InputError(path_, "line " + std::to_string(line) + ", column " + std::to_string(column + 1),
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
