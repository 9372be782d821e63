// Column specs of the XYZ and PTS text formats (io/xyz/xyz_io.h describes them): parsing a spec,
// guessing one from a first data line, and reading one from a header line. Internal to io/xyz.
// Bad specs throw std::invalid_argument naming the entry.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/point_cloud.h"

namespace candi::io::xyz {

enum class Col : uint8_t { kX, kY, kZ, kR, kG, kB, kNx, kNy, kNz, kScalar, kSkip };

struct Column {
  Col kind = Col::kSkip;
  int scalar = -1;  // kScalar: index into the schema's scalar fields
};

struct Layout {
  std::vector<Column> columns;
  PointSchema schema;  // colours, normals and float scalar fields, as the columns say
  std::string text;    // canonical spec, e.g. "x,y,z,r,g,b", for messages
};

[[noreturn]] void BadSpec(const std::string& spec, const std::string& what);

// Parses "x,y,z,r,g,b,..." (see PointReadOptions::columns). Throws std::invalid_argument naming
// the offending entry.
Layout ParseColumnSpec(const std::string& spec);

inline uint8_t& Channel(Rgb8& rgb, Col kind) {
  return kind == Col::kR ? rgb.r : kind == Col::kG ? rgb.g : rgb.b;
}
inline uint8_t Channel(const Rgb8& rgb, Col kind) { return Channel(const_cast<Rgb8&>(rgb), kind); }

// The spec guessed from a first data line's values (see xyz_io.h).
std::string GuessColumns(const std::vector<std::string_view>& tokens);

// A first line is a header when a value that would be read as a number is not one (with a spec,
// skipped and extra columns may hold text).
bool IsHeader(const std::vector<std::string_view>& tokens, const Layout* layout);

// Column names in a header line ("//X,Y,Z,R,G,B,Intensity" as CloudCompare writes it, or
// "x y z r g b" as candi does) as a layout, when they are valid names, include x, y, z, and
// match the number of values on the first point line.
std::optional<Layout> LayoutFromHeader(const std::string& header, size_t values);

// The header line candi writes: the column names, so the file reads back without a spec.
std::string HeaderLine(const std::vector<Column>& columns, const PointSchema& schema);

}  // namespace candi::io::xyz
