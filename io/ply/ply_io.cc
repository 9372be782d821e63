#include "io/ply/ply_io.h"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <limits>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/mapped_file.h"
#include "core/parallel.h"
#include "io/byte_stream.h"
#include "io/ply/ply_columns.h"
#include "io/ply/ply_header.h"
#include "io/shift_sidecar.h"

namespace candi::io {

namespace {

// Binary vertices decode in blocks of this many, in parallel.
constexpr size_t kDecodeBlock = size_t{1} << 15;

using ply::Assign;
using ply::Column;
using ply::DecodeColumn;
using ply::DecodeFastPaths;
using ply::DecodeInto;
using ply::Role;
using ply::Type;

// ---------------------------------------------------------------------------------------------
// Reader

class PlyReader : public PointReader {
 public:
  PlyReader(const std::string& path, const PointReadOptions& options);
  size_t Read(size_t max_points, PointCloud* chunk) override;
  std::optional<PointRecordLayout> record_layout() const override { return record_layout_; }
  // After all vertices: reads the faces, fanning polygons into triangles.
  std::vector<std::array<uint32_t, 3>> ReadFaces();

 private:
  [[noreturn]] void Fail(const std::string& position, const std::string& message) const {
    throw InputError(path_, position, message);
  }
  void MapColumns();
  void SetRecordLayout();
  void SkipElement(const ply::Element& element);
  size_t ReadBinary(size_t n, PointCloud* chunk);
  size_t ReadAscii(size_t n, PointCloud* chunk);
  void CompactRecord(uint64_t index, uint8_t* out);
  void CheckFinite(size_t n, const PointCloud& chunk, uint64_t first) const;
  // ASCII: the next line's tokens (false at the end of the file).
  bool NextLine(std::vector<std::string_view>* tokens);
  double ParseNumber(std::string_view token, Type type, const char* what) const;
  uint64_t ReadListCount(Type count_type, const char* element);
  std::string ReadFaceRecord(const ply::Element& element, int index_property,
                             std::vector<int64_t>* indices, std::vector<std::string_view>* tokens);

  BinaryFile file_;
  bool scalar_fields_ = true;  // PointReadOptions::scalar_fields
  ply::Header header_;
  int vertex_element_ = -1;
  std::vector<Column> columns_;  // one per vertex property (lists: kSkip)
  size_t compact_stride_ = 0;
  bool swap_ = false;
  // Binary: the file, read in place (stream_ reads from it), shared with any other pass that has
  // it mapped (MapShared: the packer's scan of the bounds and hash).
  std::shared_ptr<const MappedFile> map_;
  std::unique_ptr<ByteStream> stream_;
  std::vector<uint8_t> compact_;
  uint64_t line_ = 0;  // ASCII: the current line number
  size_t pending_consume_ = 0;  // ASCII: bytes of the current line, consumed by NextLine
  std::optional<PointRecordLayout> record_layout_;
};

PlyReader::PlyReader(const std::string& path, const PointReadOptions& options)
    : PointReader(path), file_(path), scalar_fields_(options.scalar_fields) {
  header_ = ply::ParseHeader(file_);
  vertex_element_ = header_.FindElement("vertex");
  if (vertex_element_ < 0) Fail("header", "no 'vertex' element");
  swap_ = header_.encoding == PlyEncoding::kBinaryBigEndian;
  MapColumns();
  info_.format = PointFormat::kPly;
  info_.description = std::string("PLY ") +
                      (header_.encoding == PlyEncoding::kAscii ? "ascii"
                       : swap_ ? "binary_big_endian" : "binary_little_endian") + " 1.0";
  info_.count = header_.elements[vertex_element_].count;
  const int face = header_.FindElement("face");
  info_.face_count = face >= 0 ? header_.elements[face].count : 0;
  info_.meta.comments = header_.comments;
  info_.meta.crs = header_.crs;
  if (header_.shift) {
    info_.frame = *header_.shift;
  } else if (auto sidecar = ReadShiftSidecar(path)) {
    info_.frame = *sidecar;
  }
  line_ = header_.header_lines;
  if (header_.encoding == PlyEncoding::kAscii) {
    stream_ = std::make_unique<ByteStream>(file_);  // lines of at most 1 MiB, in a buffer
  } else {
    // Binary records are decoded where the page cache holds them: no copy into a buffer.
    map_ = MapShared(path);
    stream_ = std::make_unique<ByteStream>(*map_, std::min(file_.position(), map_->size()));
  }
  for (int e = 0; e < vertex_element_; ++e) SkipElement(header_.elements[e]);
  SetRecordLayout();
}

void PlyReader::SetRecordLayout() {
  const ply::Element& vertex = header_.elements[vertex_element_];
  if (header_.encoding != PlyEncoding::kBinaryLittleEndian || vertex.HasLists()) return;
  PointRecordLayout layout;
  layout.first_byte = stream_->offset();
  layout.stride = vertex.FixedSize();
  layout.count = info_.count;
  int axes = 0;
  for (const Column& c : columns_) {
    const int axis = c.role == Role::kX ? 0 : c.role == Role::kY ? 1 : c.role == Role::kZ ? 2 : -1;
    const int channel = c.role == Role::kR ? 0 : c.role == Role::kG ? 1 : c.role == Role::kB ? 2 : -1;
    if (axis >= 0) {
      if (c.type != Type::kFloat32 && c.type != Type::kFloat64) return;
      const auto coordinates = c.type == Type::kFloat32 ? PointRecordLayout::Coordinates::kFloat32
                                                        : PointRecordLayout::Coordinates::kFloat64;
      if (axes > 0 && coordinates != layout.coordinates) return;  // x, y and z of one type
      layout.coordinates = coordinates;
      ++axes;
      layout.xyz[axis] = c.offset;
    }
    if (channel >= 0) {
      if (c.type != Type::kUint8) return;
      layout.rgb[channel] = static_cast<int>(c.offset);
    }
  }
  // Each coordinate and colour channel named once (a header may repeat a property and miss
  // another): else the reader's own decoding, never a record offset left unset.
  int channels = 0;
  for (const Column& c : columns_) channels += c.role == Role::kR || c.role == Role::kG || c.role == Role::kB;
  const bool colour = layout.rgb[0] >= 0 && layout.rgb[1] >= 0 && layout.rgb[2] >= 0;
  if (axes != 3 || !(channels == 0 || (channels == 3 && colour))) return;
  const size_t x = layout.xyz[0], y = layout.xyz[1], z = layout.xyz[2];
  if (x == y || y == z || x == z) return;  // an axis named twice, another not at all
  record_layout_ = layout;
}

void PlyReader::MapColumns() {
  const ply::Element& vertex = header_.elements[vertex_element_];
  PointSchema& schema = info_.schema;
  schema.position_type = ScalarType::kFloat32;
  int found_xyz = 0, found_rgb = 0, found_normals = 0;
  for (const ply::Property& p : vertex.properties) {
    Column c;
    c.type = p.type;
    c.offset = compact_stride_;
    const std::string& n = p.name;
    if (p.is_list) {
      columns_.push_back(c);  // skipped: OpenMVS's view_indices, view_weights
      continue;
    }
    compact_stride_ += ply::TypeSize(p.type);
    if (n == "x" || n == "y" || n == "z") {
      c.role = n == "x" ? Role::kX : n == "y" ? Role::kY : Role::kZ;
      found_xyz++;
      if (p.type != Type::kFloat32) schema.position_type = ScalarType::kFloat64;
    } else if (n == "red" || n == "green" || n == "blue" || n == "diffuse_red" ||
               n == "diffuse_green" || n == "diffuse_blue") {
      c.role = n.back() == 'd' ? Role::kR : n.back() == 'n' ? Role::kG : Role::kB;
      found_rgb++;
    } else if (n == "alpha" || n == "diffuse_alpha") {
      c.role = Role::kA;
      schema.alphas = true;
    } else if (n == "nx" || n == "ny" || n == "nz") {
      c.role = n == "nx" ? Role::kNx : n == "ny" ? Role::kNy : Role::kNz;
      found_normals++;
    } else if (n == "layer" && p.type != Type::kFloat32 && p.type != Type::kFloat64) {
      c.role = Role::kLayer;
      schema.layers = true;
    } else if (!scalar_fields_) {
      // skipped: geometry and colour only
    } else {
      std::string name = n.rfind("scalar_", 0) == 0 && n.size() > 7 ? n.substr(7) : n;
      if (schema.ScalarIndex(name) >= 0) name = n;  // both "scalar_q" and "q": keep the full name
      const bool wide = p.type == Type::kFloat64 || p.type == Type::kInt32 || p.type == Type::kUint32;
      c.role = Role::kScalar;
      c.scalar = static_cast<int>(schema.scalars.size());
      schema.scalars.push_back({name, wide ? ScalarType::kFloat64 : ScalarType::kFloat32});
    }
    columns_.push_back(c);
  }
  if (found_xyz != 3) Fail("header", "vertex element lacks x, y or z");
  if (found_rgb != 0 && found_rgb != 3) Fail("header", "vertex colour needs red, green and blue");
  if (found_normals != 0 && found_normals != 3) Fail("header", "vertex normals need nx, ny and nz");
  schema.colors = found_rgb == 3;
  schema.normals = found_normals == 3;
  if (schema.alphas && !schema.colors) {
    schema.alphas = false;  // alpha without colour: keep it as a scalar-less skip
    for (Column& c : columns_) if (c.role == Role::kA) c.role = Role::kSkip;
  }
}

size_t PlyReader::Read(size_t max_points, PointCloud* chunk) {
  CANDI_CHECK(max_points > 0);
  PrepareChunk(chunk);
  const uint64_t left = info_.count - points_read_;
  const size_t n = static_cast<size_t>(std::min<uint64_t>(left, max_points));
  chunk->Resize(n);
  if (n == 0) return 0;
  const size_t got = header_.encoding == PlyEncoding::kAscii ? ReadAscii(n, chunk)
                                                             : ReadBinary(n, chunk);
  CheckFinite(got, *chunk, points_read_);
  points_read_ += got;
  return got;
}

void PlyReader::CheckFinite(size_t n, const PointCloud& chunk, uint64_t first) const {
  // A value is finite unless its exponent bits are all ones: one integer pass, then a search on
  // failure.
  constexpr uint64_t kExponent = 0x7ff0000000000000ULL;
  const auto* bits = reinterpret_cast<const uint64_t*>(chunk.positions.data());
  // Adding one to an all-ones exponent carries into the sign bit: add/and/or vectorize. Blocks
  // in parallel; the first bad vertex is then found in order, so the message does not depend on
  // the threads.
  std::atomic<bool> any_bad{false};
  ParallelFor(size_t{0}, (n + kDecodeBlock - 1) / kDecodeBlock, [&](size_t b) {
    const uint64_t* word = bits + 3 * b * kDecodeBlock;
    const size_t words = 3 * (std::min(n, (b + 1) * kDecodeBlock) - b * kDecodeBlock);
    uint64_t bad = 0;
    for (size_t j = 0; j < words; ++j) bad |= ((word[j] & kExponent) + (1ULL << 52)) & (1ULL << 63);
    if (bad) any_bad = true;
  });
  if (!any_bad) return;
  for (size_t i = 0; i < n; ++i) {
    if (!chunk.positions[i].allFinite()) {
      Fail("vertex " + std::to_string(first + i), "coordinate is NaN or infinite");
    }
  }
}

size_t PlyReader::ReadBinary(size_t n, PointCloud* chunk) {
  const ply::Element& vertex = header_.elements[vertex_element_];
  const uint8_t* records;
  size_t stride;
  if (!vertex.HasLists()) {
    stride = vertex.FixedSize();
    // Bound one read to ~64 MiB; Read() may return fewer points than asked.
    n = std::min(n, std::max<size_t>(1, (64u << 20) / std::max<size_t>(stride, 1)));
    if (!stream_->Ensure(n * stride)) {
      Fail("byte " + std::to_string(stream_->offset() + stream_->available()),
           "file ends inside vertex " + std::to_string(points_read_ + stream_->available() / stride) +
               " of " + std::to_string(info_.count));
    }
    map_->CheckSize(stream_->offset() + n * stride, "vertex records");  // SIGBUS otherwise
    map_->WillNeed(stream_->offset(), n * stride);
    records = stream_->data();
  } else {
    stride = compact_stride_;
    compact_.resize(n * stride);
    for (size_t i = 0; i < n; ++i) CompactRecord(points_read_ + i, compact_.data() + i * stride);
    records = compact_.data();
  }
  chunk->Resize(n);
  // Blocks of records decode independently (each into its own range of the chunk), so they run
  // in parallel; the result does not depend on the thread count.
  const size_t blocks = (n + kDecodeBlock - 1) / kDecodeBlock;
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    const size_t first = b * kDecodeBlock, m = std::min(kDecodeBlock, n - first);
    std::vector<bool> done(columns_.size(), false);
    if (!swap_) DecodeFastPaths(columns_, records + first * stride, stride, m, first, chunk, &done);
    for (size_t k = 0; k < columns_.size(); ++k) {
      if (!done[k]) DecodeInto(columns_[k], records + first * stride, stride, m, swap_, first, chunk);
    }
  });
  if (!vertex.HasLists()) stream_->Consume(n * stride);
  return n;
}

// Copies the non-list properties of one variable-size record into the compact layout.
void PlyReader::CompactRecord(uint64_t index, uint8_t* out) {
  const ply::Element& vertex = header_.elements[vertex_element_];
  for (size_t k = 0; k < vertex.properties.size(); ++k) {
    const ply::Property& p = vertex.properties[k];
    if (p.is_list) {
      const uint64_t count = ReadListCount(p.count_type, "vertex");
      const uint64_t bytes = count * ply::TypeSize(p.type);
      if (!stream_->Ensure(bytes)) {
        Fail("byte " + std::to_string(stream_->offset()),
             "file ends inside list '" + p.name + "' of vertex " + std::to_string(index));
      }
      stream_->Consume(bytes);
      continue;
    }
    const size_t size = ply::TypeSize(p.type);
    if (!stream_->Ensure(size)) {
      Fail("byte " + std::to_string(stream_->offset()),
           "file ends inside vertex " + std::to_string(index) + " of " + std::to_string(info_.count));
    }
    std::memcpy(out + columns_[k].offset, stream_->data(), size);
    stream_->Consume(size);
  }
}

uint64_t PlyReader::ReadListCount(Type count_type, const char* element) {
  const size_t size = ply::TypeSize(count_type);
  if (!stream_->Ensure(size)) {
    Fail("byte " + std::to_string(stream_->offset()),
         std::string("file ends inside a list of ") + element);
  }
  int64_t count = 0;
  DecodeColumn(count_type, stream_->data(), size, 1, swap_,
               [&count](size_t, auto v) { count = static_cast<int64_t>(v); });
  if (count < 0) {
    Fail("byte " + std::to_string(stream_->offset()),
         "negative list length " + std::to_string(count) + " in " + element);
  }
  stream_->Consume(size);
  return static_cast<uint64_t>(count);
}

bool PlyReader::NextLine(std::vector<std::string_view>* tokens) {
  constexpr size_t kMaxLine = 1 << 20;
  stream_->Consume(pending_consume_);
  pending_consume_ = 0;
  tokens->clear();
  size_t scanned = 0;
  const char* nl = nullptr;
  while (true) {
    const auto* begin = reinterpret_cast<const char*>(stream_->data());
    // (An empty stream has no buffer yet: memchr of a null pointer is undefined even for 0 bytes.)
    nl = stream_->available() > scanned
             ? static_cast<const char*>(std::memchr(begin + scanned, '\n', stream_->available() - scanned))
             : nullptr;
    if (nl != nullptr) break;
    scanned = stream_->available();
    if (scanned > kMaxLine) Fail("line " + std::to_string(line_ + 1), "line longer than 1 MiB");
    if (!stream_->Ensure(scanned + 1)) break;  // end of file: what is left is the last line
  }
  if (stream_->available() == 0) return false;
  const auto* begin = reinterpret_cast<const char*>(stream_->data());
  const char* end = nl != nullptr ? nl : begin + stream_->available();
  // The tokens point into the stream's buffer: valid until the next NextLine.
  for (const char* p = begin; p < end;) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\r')) ++p;
    const char* start = p;
    while (p < end && *p != ' ' && *p != '\t' && *p != '\r') ++p;
    if (p > start) tokens->emplace_back(start, static_cast<size_t>(p - start));
  }
  pending_consume_ = static_cast<size_t>(end - begin) + (nl != nullptr ? 1 : 0);
  ++line_;
  return true;
}

double PlyReader::ParseNumber(std::string_view token, Type type, const char* what) const {
  double value = 0.0;
  auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size()) {
    Fail("line " + std::to_string(line_), "'" + std::string(token) + "' is not a number (" + what + ")");
  }
  if (type == Type::kFloat32 || type == Type::kFloat64) return value;
  double lo = 0, hi = 0;
  switch (type) {
    case Type::kInt8: lo = -128; hi = 127; break;
    case Type::kUint8: hi = 255; break;
    case Type::kInt16: lo = -32768; hi = 32767; break;
    case Type::kUint16: hi = 65535; break;
    case Type::kInt32: lo = -2147483648.0; hi = 2147483647.0; break;
    default: hi = 4294967295.0; break;
  }
  if (!(value >= lo && value <= hi) || value != std::floor(value)) {
    Fail("line " + std::to_string(line_), "value " + std::string(token) + " of " + what +
                                              " is not a " + ply::TypeName(type));
  }
  return value;
}

size_t PlyReader::ReadAscii(size_t n, PointCloud* chunk) {
  const ply::Element& vertex = header_.elements[vertex_element_];
  std::vector<std::string_view> tokens;
  for (size_t i = 0; i < n; ++i) {
    do {
      if (!NextLine(&tokens)) {
        Fail("line " + std::to_string(line_ + 1), "file ends after " +
             std::to_string(points_read_ + i) + " of " + std::to_string(info_.count) + " vertices");
      }
    } while (tokens.empty());
    size_t t = 0;
    for (size_t k = 0; k < vertex.properties.size(); ++k) {
      const ply::Property& p = vertex.properties[k];
      if (t >= tokens.size()) {
        Fail("line " + std::to_string(line_), "too few values: property '" + p.name + "' missing");
      }
      if (p.is_list) {
        const double count = ParseNumber(tokens[t++], p.count_type, p.name.c_str());
        t += static_cast<size_t>(count);
        continue;
      }
      Assign(columns_[k], i, ParseNumber(tokens[t++], p.type, p.name.c_str()), chunk);
    }
    if (t != tokens.size()) {
      Fail("line " + std::to_string(line_), std::to_string(tokens.size()) + " values, expected " +
                                                std::to_string(t) + " for vertex " +
                                                std::to_string(points_read_ + i));
    }
  }
  return n;
}

void PlyReader::SkipElement(const ply::Element& element) {
  if (header_.encoding == PlyEncoding::kAscii) {
    std::vector<std::string_view> tokens;
    for (uint64_t i = 0; i < element.count; ++i) {
      if (!NextLine(&tokens)) {
        Fail("line " + std::to_string(line_ + 1), "file ends inside element '" + element.name + "'");
      }
    }
    return;
  }
  if (!element.HasLists()) {
    uint64_t left = element.count * element.FixedSize();
    while (left > 0) {
      const size_t step = static_cast<size_t>(std::min<uint64_t>(left, 8u << 20));
      if (!stream_->Ensure(step)) {
        Fail("byte " + std::to_string(stream_->offset()), "file ends inside element '" + element.name + "'");
      }
      stream_->Consume(step);
      left -= step;
    }
    return;
  }
  for (uint64_t i = 0; i < element.count; ++i) {
    for (const ply::Property& p : element.properties) {
      const uint64_t count = p.is_list ? ReadListCount(p.count_type, element.name.c_str()) : 1;
      const uint64_t bytes = count * ply::TypeSize(p.type);
      if (!stream_->Ensure(bytes)) {
        Fail("byte " + std::to_string(stream_->offset()), "file ends inside element '" + element.name + "'");
      }
      stream_->Consume(bytes);
    }
  }
}

// Reads one face record's index list (other face properties are skipped).
// A face's vertex index as stored (any PLY type, float lists included): a value that is not an
// integer in int64's range becomes -1, which FaceCollector reports as outside the vertex range
// (casting it would be undefined behaviour).
int64_t VertexIndex(double v) {
  return v >= -9.0e18 && v <= 9.0e18 && v == std::floor(v) ? static_cast<int64_t>(v) : -1;
}

class FaceCollector {
 public:
  FaceCollector(uint64_t vertex_count, std::vector<std::array<uint32_t, 3>>* faces)
      : vertex_count_(vertex_count), faces_(faces) {}
  // Fans polygon `indices` into triangles; returns an error message or "".
  std::string Add(const std::vector<int64_t>& indices) {
    for (int64_t v : indices) {
      if (v < 0 || static_cast<uint64_t>(v) >= vertex_count_) {
        return "vertex index " + std::to_string(v) + " outside [0, " + std::to_string(vertex_count_) + ")";
      }
    }
    if (indices.size() < 3) {
      ++degenerate_;
      return "";
    }
    for (size_t k = 1; k + 1 < indices.size(); ++k) {
      faces_->push_back({static_cast<uint32_t>(indices[0]), static_cast<uint32_t>(indices[k]),
                         static_cast<uint32_t>(indices[k + 1])});
    }
    return "";
  }
  uint64_t degenerate() const { return degenerate_; }

 private:
  uint64_t vertex_count_;
  std::vector<std::array<uint32_t, 3>>* faces_;
  uint64_t degenerate_ = 0;
};

std::vector<std::array<uint32_t, 3>> PlyReader::ReadFaces() {
  PointCloud sink;
  while (points_read_ < info_.count) Read(1 << 20, &sink);
  std::vector<std::array<uint32_t, 3>> faces;
  FaceCollector collector(info_.count, &faces);
  for (size_t e = vertex_element_ + 1; e < header_.elements.size(); ++e) {
    const ply::Element& element = header_.elements[e];
    int index_property = -1;
    for (size_t k = 0; k < element.properties.size(); ++k) {
      const ply::Property& p = element.properties[k];
      if (p.is_list && (p.name == "vertex_indices" || p.name == "vertex_index")) index_property = k;
    }
    if (element.name != "face" || index_property < 0) {
      SkipElement(element);
      continue;
    }
    faces.reserve(element.count);
    std::vector<int64_t> indices;
    std::vector<std::string_view> tokens;
    for (uint64_t f = 0; f < element.count; ++f) {
      indices.clear();
      const std::string position = ReadFaceRecord(element, index_property, &indices, &tokens);
      const std::string error = collector.Add(indices);
      if (!error.empty()) Fail(position, "face " + std::to_string(f) + ": " + error);
    }
    break;
  }
  if (collector.degenerate() > 0) {
    LogWarning(path_ + ": skipped " + std::to_string(collector.degenerate()) +
               " faces with fewer than 3 vertices");
  }
  return faces;
}

std::string PlyReader::ReadFaceRecord(const ply::Element& element, int index_property,
                                      std::vector<int64_t>* indices,
                                      std::vector<std::string_view>* tokens) {
  if (header_.encoding == PlyEncoding::kAscii) {
    if (!NextLine(tokens)) Fail("line " + std::to_string(line_ + 1), "file ends inside the faces");
    const std::string position = "line " + std::to_string(line_);
    size_t t = 0;
    for (size_t k = 0; k < element.properties.size(); ++k) {
      const ply::Property& p = element.properties[k];
      if (t >= tokens->size()) Fail(position, "too few values in face");
      const size_t count = p.is_list ? static_cast<size_t>(ParseNumber((*tokens)[t++], p.count_type, p.name.c_str())) : 1;
      if (t + count > tokens->size()) Fail(position, "too few values in face list '" + p.name + "'");
      for (size_t j = 0; j < count; ++j, ++t) {
        const double v = ParseNumber((*tokens)[t], p.type, p.name.c_str());
        if (static_cast<int>(k) == index_property) indices->push_back(VertexIndex(v));
      }
    }
    return position;
  }
  const std::string position = "byte " + std::to_string(stream_->offset());
  for (size_t k = 0; k < element.properties.size(); ++k) {
    const ply::Property& p = element.properties[k];
    const uint64_t count = p.is_list ? ReadListCount(p.count_type, "face") : 1;
    const size_t size = ply::TypeSize(p.type);
    if (!stream_->Ensure(count * size)) Fail(position, "file ends inside the faces");
    if (static_cast<int>(k) == index_property) {
      DecodeColumn(p.type, stream_->data(), size, count, swap_,
                   [indices](size_t, auto v) { indices->push_back(VertexIndex(static_cast<double>(v))); });
    }
    stream_->Consume(count * size);
  }
  return position;
}

}  // namespace

std::unique_ptr<PointReader> OpenPlyReader(const std::string& path,
                                           const PointReadOptions& options) {
  return std::make_unique<PlyReader>(path, options);
}

TriMesh ReadPlyMesh(const std::string& path) {
  if (DetectPointFormat(path) != PointFormat::kPly) throw InputError(path, "", "not a PLY file");
  PlyReader reader(path, PointReadOptions{});
  TriMesh mesh;
  mesh.vertices.SetSchema(reader.info().schema);
  mesh.vertices.frame = reader.info().frame;
  mesh.vertices.meta = reader.info().meta;
  mesh.vertices.Reserve(reader.info().count);
  PointCloud chunk;
  while (reader.Read(1 << 20, &chunk) > 0) mesh.vertices.Append(chunk);
  mesh.faces = reader.ReadFaces();
  return mesh;
}

}  // namespace candi::io
