// Column-wise conversion between LAS point records and PointCloud arrays, for the LAS codec
// (io/las/las_reader.cc, las_writer.cc).
//
// Each attribute is a LasColumn: a raw type at a byte offset in the record (or a bit field of a
// byte) bound to a scalar field or a normal component. Decoding and encoding run one tight
// strided loop per column over a block of records: a per-point switch over the attributes is
// several times slower. Record layouts: ASPRS LAS 1.4 R15, tables 7-16.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "io/las/las_header.h"

namespace candi::io {

// Records decoded or encoded at a time. Each attribute is converted in its own tight loop over
// the block (a per-point switch is several times slower), and a block's bytes (~140 kB for
// format 3) stay in L2 while the loops revisit them.
inline constexpr size_t kLasBlockRecords = 4096;

enum class LasRaw : uint8_t { kU8, kI8, kU16, kI16, kU32, kI32, kU64, kI64, kF32, kF64 };

// One attribute of a point record and where it goes in (or comes from) a PointCloud.
struct LasColumn {
  LasRaw raw = LasRaw::kU8;
  int offset = 0;     // byte offset in the record
  uint8_t shift = 0;  // a bit field (byte >> shift) & mask when mask != 0
  uint8_t mask = 0;
  int scalar = -1;       // scalar field index in the schema, or
  int normal_axis = -1;  // a normal component (extra bytes nx, ny, nz)
  double scale = 1.0;    // reading: value = raw * scale + add; writing: raw = value * scale
  double add = 0.0;
  double constant = 0.0;     // writing, when the schema has no such field
  std::vector<float> table;  // reading one-byte attributes: the value of each byte value
};

struct LasStandardColumn {
  const char* name;  // a las_field name
  LasRaw raw;
  int offset;
  uint8_t shift, mask;
};

// The column of a standard attribute (raw type, offset, bit field), not yet bound to a field.
inline LasColumn ColumnOf(const LasStandardColumn& s) {
  LasColumn c;
  c.raw = s.raw;
  c.offset = s.offset;
  c.shift = s.shift;
  c.mask = s.mask;
  return c;
}

// The standard attributes of a point format (0-10) as scalar fields, gps_time and nir included.
std::vector<LasStandardColumn> LasStandardColumns(int format);
// The raw type of a numeric Extra Bytes data type (1-10).
LasRaw LasRawOfExtraBytesType(int data_type);
// The scalar type that holds an Extra Bytes field without loss.
ScalarType LasScalarTypeOf(const LasExtraBytes& e);
// Gives a one-byte column (kU8/kI8, unscaled) its decoding table; other columns are left alone.
void FillLasByteTable(LasColumn* c);

// LAS integer coordinates to positions: (X + offset/scale) / (1/scale) when every axis has a
// decimal scale (1/scale an integer) and an offset that is a multiple of it, the correctly
// rounded decimal (0.001 * 3272 is 3.2720000000000002, 3272 / 1000 is 3.272); X * scale + offset
// otherwise. The one definition for the reader and the render archive packer.
struct LasPositionDecoder {
  LasPositionDecoder() = default;
  LasPositionDecoder(const Eigen::Vector3d& scale, const Eigen::Vector3d& offset);
  bool decimal = false;
  double divisor[3] = {1, 1, 1}, integer_offset[3] = {0, 0, 0};  // decimal
  double scale[3] = {1, 1, 1}, offset[3] = {0, 0, 0};             // otherwise
  double Axis(int a, int32_t x) const {
    return decimal ? (x + integer_offset[a]) / divisor[a] : x * scale[a] + offset[a];
  }
  bool operator==(const LasPositionDecoder& o) const;
};

// Decoding n records (stride bytes apart) into entries [first, first + n) of the chunk.
void DecodeLasPositions(const uint8_t* records, size_t stride, size_t n,
                        const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                        Eigen::Vector3d* out);
// Colour at `colors` (R, G, B uint16) shifted right by `shift` (8: 16-bit colour, 0: 8-bit).
void DecodeLasColors(const uint8_t* colors, size_t stride, size_t n, int shift, Rgb8* out);
void DecodeLasColumn(const LasColumn& c, const uint8_t* records, size_t stride, size_t n,
                     size_t first, PointCloud* chunk);

// Encoding entries [first, first + n) of the chunk into n zeroed records (bit fields are OR-ed,
// so fields sharing a byte are encoded separately). Values are rounded half away from zero and
// clamped into the raw type (or the bit field); NaN becomes the lowest value.
void EncodeLasColumn(const LasColumn& c, const PointCloud& chunk, size_t first, size_t n,
                     uint8_t* records, size_t stride);
// Quantizes n positions, X = round((position + origin - offset) / scale) per axis, into three
// little-endian int32 at the start of each record, extending [lo, hi] (three values each).
// Returns the first point that does not fit int32 (or is NaN), or n.
size_t EncodeLasPositions(const Eigen::Vector3d* positions, size_t n, const Eigen::Vector3d& origin,
                          const Eigen::Vector3d& offset, const Eigen::Vector3d& scale, uint8_t* out,
                          size_t stride, int32_t* lo, int32_t* hi);

}  // namespace candi::io
