// The packer's intermediate points (render/archive_pack.cc), private to it: the three record
// forms a point takes between reading and quantizing, and the Morton grid over the archive's
// bounds (the external sort's cell files are core/spill_file.h's).
#pragma once


#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>

#include <Eigen/Core>

#include "core/check.h"
#include "core/morton.h"
#include "io/las/las_columns.h"
#include "render/archive.h"

namespace candi::render::pack_internal {

// The points between reading and encoding (in cell files and in memory), in one of three forms.
// WidePoint: the archive-frame position in double, any input. CompactPoint: when every input
// point is a float in one frame shared by all inputs (binary PLY with float x, y, z, the usual
// photogrammetry output), that float; adding the shift from that frame to the archive's gives
// the very doubles WidePoint would hold, so the archive is the same, from 16 bytes a point
// instead of 28. LasPoint: when every input is LAS with one scale and offset, its integers,
// decoded as the LAS reader decodes them (16 bytes as well).
// How records give positions in the archive frame: CompactPoint adds `shift` to its floats,
// LasPoint decodes its integers with `las` (as the LAS reader does) and adds `shift`, WidePoint
// holds the position itself.
struct RecordFrame {
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  io::LasPositionDecoder las;
};

#pragma pack(push, 1)
struct WidePoint {
  double x, y, z;
  uint32_t rgb;
  // By value: a reference to a member of a packed struct may be misaligned (undefined behaviour
  // that UBSan reports where Eigen's constructors take `const double&`).
  Eigen::Vector3d Position(const RecordFrame& /*frame*/) const { return Eigen::Vector3d(double{x}, double{y}, double{z}); }
};
#pragma pack(pop)
static_assert(sizeof(WidePoint) == 28, "WidePoint must be packed");

struct CompactPoint {
  float x, y, z;
  uint32_t rgb;
  Eigen::Vector3d Position(const RecordFrame& f) const {
    return Eigen::Vector3d(double{x}, double{y}, double{z}) + f.shift;
  }
};
static_assert(sizeof(CompactPoint) == 16, "CompactPoint must be 16 bytes");

// A LAS point record's integers (every input LAS with one scale and offset, read directly).
struct LasPoint {
  int32_t x, y, z;
  uint32_t rgb;
  Eigen::Vector3d Position(const RecordFrame& f) const {
    return Eigen::Vector3d(f.las.Axis(0, x), f.las.Axis(1, y), f.las.Axis(2, z)) + f.shift;
  }
};
static_assert(sizeof(LasPoint) == 16, "LasPoint must be 16 bytes");

constexpr int kMortonBits = 21;  // per axis; 63-bit codes, 21 levels of 3 bits

struct MortonGrid {
  Eigen::Vector3d min, scale;  // cells per metre
  // The point's cell on each axis: 21 bits.
  void Quantize(const Eigen::Vector3d& p, uint64_t q[3]) const {
    const double top = static_cast<double>((1 << kMortonBits) - 1);
    for (int a = 0; a < 3; ++a) q[a] = static_cast<uint64_t>(std::clamp((p[a] - min[a]) * scale[a], 0.0, top));
  }
  uint64_t Code(const Eigen::Vector3d& p) const {
    uint64_t q[3];
    Quantize(p, q);
    return MortonCode21(q[0], q[1], q[2]);
  }
};

// The key of a point at a level: the code's top 3 * levels bits.
inline uint64_t Prefix(uint64_t code, int levels) { return levels == 0 ? 0 : code >> (63 - 3 * levels); }

// Quantizes points[0, n) on a chunk's quantizer into words[0, n) (ChunkQuantizer::Encode).
// Compiled for AVX2 as well (the loader picks), where Encode's rounding is one instruction rather
// than a libm call: the same words.
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const WidePoint* points, size_t n, uint64_t* words);
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const CompactPoint* points, size_t n, uint64_t* words);
void Encode(const ChunkQuantizer& q, const RecordFrame& f, const LasPoint* points, size_t n, uint64_t* words);

// MortonGrid::Code of each point's Position(f) into codes[0, n), vectorized (compiled for AVX2
// as well): the same codes.
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const WidePoint* points, size_t n, uint64_t* codes);
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const CompactPoint* points, size_t n, uint64_t* codes);
void MortonCodes(const MortonGrid& g, const RecordFrame& f, const LasPoint* points, size_t n, uint64_t* codes);

// (MortonCodes >> 3 * shift) & (2^(3 * levels) - 1) into cells[0, n), for 1 <= levels <= 3 and
// shift + levels <= kMortonBits: the cell of each point `levels` below a node `shift` levels
// above the finest. Cheaper than the codes (32-bit lanes, only those bits), the same values.
void MortonCells(const MortonGrid& g, const RecordFrame& f, const WidePoint* points, size_t n, int shift, int levels,
                 uint16_t* cells);
void MortonCells(const MortonGrid& g, const RecordFrame& f, const CompactPoint* points, size_t n, int shift,
                 int levels, uint16_t* cells);
void MortonCells(const MortonGrid& g, const RecordFrame& f, const LasPoint* points, size_t n, int shift, int levels,
                 uint16_t* cells);

// The box of points[0, n) (n > 0): the positions' min and max on each axis.
template <typename P>
Box3d ChunkBox(const P* points, size_t n, const RecordFrame& f) {
  Box3d box;
  for (size_t i = 0; i < n; ++i) box.Extend(points[i].Position(f));
  return box;
}
// LAS: a position is monotonic in its integer on each axis (increasing, or decreasing for a
// negative scale), so the box is that of the integers' extremes, decoded: the same doubles.
Box3d ChunkBox(const LasPoint* points, size_t n, const RecordFrame& f);

// Whether v is a float (so CompactPoint holds it exactly); false for NaN and beyond float's range.
inline bool IsFloat(double v) {
  return std::abs(v) <= std::numeric_limits<float>::max() && double{static_cast<float>(v)} == v;
}
inline bool IsFloat(const Eigen::Vector3d& p) { return IsFloat(p.x()) && IsFloat(p.y()) && IsFloat(p.z()); }

}  // namespace candi::render::pack_internal
