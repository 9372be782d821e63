// The PLY header: elements, properties and their types; parsing and writing.
// Internal to the PLY codec (io/ply/ply_io.cc), exposed for its tests.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/local_frame.h"
#include "io/point_file.h"

namespace candi {
class BinaryFile;
}

namespace candi::io::ply {

enum class Type : uint8_t { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
size_t TypeSize(Type type);
const char* TypeName(Type type);  // "char", "uchar", ... as written by candi
// Parses a PLY type name (both "uchar" and "uint8" spellings); false when unknown.
bool ParseType(const std::string& name, Type* type);

struct Property {
  std::string name;
  Type type = Type::kFloat32;  // value type (list elements for lists)
  bool is_list = false;
  Type count_type = Type::kUint8;  // lists only
};

struct Element {
  std::string name;
  uint64_t count = 0;
  std::vector<Property> properties;
  bool HasLists() const;
  size_t FixedSize() const;  // bytes of one record without lists (lists count their count field)
};

struct Header {
  PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian;
  std::vector<Element> elements;
  std::vector<std::string> comments;   // comment lines (text after "comment ")
  std::optional<LocalFrame> shift;     // from "comment candi_shift x y z"
  std::string crs;                     // from "comment candi_crs <CRS>" (PointCloudMeta::crs)
  uint64_t data_offset = 0;            // byte where the body starts
  int header_lines = 0;                // lines up to and including end_header
  int FindElement(const std::string& name) const;  // -1 when absent
};

// Parses the header at the start of the file. Throws InputError(path, "line N", ...) for an
// unknown format, an unknown type, a property outside an element, a missing end_header, and
// counts the file cannot hold (a fixed lower bound of the body size exceeds the file).
Header ParseHeader(BinaryFile& file);

// Text of a header for writing. When vertex_count_width > 0, the vertex count is written
// left-aligned and padded with spaces to that width (so it can be patched in place later).
std::string FormatHeader(const Header& header, int vertex_count_width = 0);

}  // namespace candi::io::ply
