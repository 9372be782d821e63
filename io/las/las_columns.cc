#include "io/las/las_columns.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <limits>
#include <type_traits>

#include "core/binary_file.h"
#include "core/check.h"
#include "io/las/las_io.h"

namespace candi::io {

namespace {

// LAS 1.4 R15 tables 7 (formats 0-5) and 13 (formats 6-10).
constexpr LasStandardColumn kLegacyColumns[] = {
    {las_field::kIntensity, LasRaw::kU16, 12, 0, 0},
    {las_field::kReturnNumber, LasRaw::kU8, 14, 0, 7},
    {las_field::kNumberOfReturns, LasRaw::kU8, 14, 3, 7},
    {las_field::kScanDirection, LasRaw::kU8, 14, 6, 1},
    {las_field::kEdgeOfFlightLine, LasRaw::kU8, 14, 7, 1},
    {las_field::kClassification, LasRaw::kU8, 15, 0, 31},
    {las_field::kClassFlags, LasRaw::kU8, 15, 5, 7},
    {las_field::kUserData, LasRaw::kU8, 17, 0, 0},
    {las_field::kScanAngleRank, LasRaw::kI8, 16, 0, 0},
    {las_field::kPointSourceId, LasRaw::kU16, 18, 0, 0},
};
constexpr LasStandardColumn kExtendedColumns[] = {
    {las_field::kIntensity, LasRaw::kU16, 12, 0, 0},
    {las_field::kReturnNumber, LasRaw::kU8, 14, 0, 15},
    {las_field::kNumberOfReturns, LasRaw::kU8, 14, 4, 15},
    {las_field::kScanDirection, LasRaw::kU8, 15, 6, 1},
    {las_field::kEdgeOfFlightLine, LasRaw::kU8, 15, 7, 1},
    {las_field::kClassification, LasRaw::kU8, 16, 0, 0},
    {las_field::kClassFlags, LasRaw::kU8, 15, 0, 15},
    {las_field::kScannerChannel, LasRaw::kU8, 15, 4, 3},
    {las_field::kUserData, LasRaw::kU8, 17, 0, 0},
    {las_field::kScanAngle, LasRaw::kI16, 18, 0, 0},
    {las_field::kPointSourceId, LasRaw::kU16, 20, 0, 0},
};

template <typename T>
void DecodeColumn(const LasColumn& c, const uint8_t* records, size_t stride, size_t n, size_t first,
                  PointCloud* chunk) {
  const uint8_t* p = records + c.offset;
  const double scale = c.scale, add = c.add;
  if (c.normal_axis >= 0) {
    float* out = chunk->normals[first].data() + c.normal_axis;
    for (size_t i = 0; i < n; ++i) {
      out[3 * i] = static_cast<float>(LoadLE<T>(p + i * stride) * scale + add);
    }
    return;
  }
  ScalarField& field = chunk->scalars[c.scalar];
  if (field.spec.type == ScalarType::kFloat64) {
    double* out = field.f64.data() + first;
    for (size_t i = 0; i < n; ++i) out[i] = static_cast<double>(LoadLE<T>(p + i * stride));
    if (scale != 1.0 || add != 0.0) {
      for (size_t i = 0; i < n; ++i) out[i] = out[i] * scale + add;
    }
    return;
  }
  float* out = field.f32.data() + first;  // unscaled types of at most 16 bits, or float
  if (!c.table.empty()) {
    const float* table = c.table.data();
    for (size_t i = 0; i < n; ++i) out[i] = table[p[i * stride]];
    return;
  }
  for (size_t i = 0; i < n; ++i) out[i] = static_cast<float>(LoadLE<T>(p + i * stride));
}

// Clamps into [lo, hi] (NaN gives lo) and rounds half away from zero, without branches.
inline int64_t Quantize(double v, double lo, double hi) {
  const double clamped = std::min(std::max(lo, v), hi);
  return static_cast<int64_t>(clamped + std::copysign(0.5, clamped));
}

template <typename T>
T ToRaw(double v) {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(v);
  } else {
    return static_cast<T>(
        Quantize(v, std::numeric_limits<T>::lowest(), std::numeric_limits<T>::max()));
  }
}

// Parameters are copied to locals: the byte stores may alias anything and would otherwise
// reload them on every point.
template <typename T, typename Src>
void EncodeValues(const LasColumn& c, const Src* src, size_t src_stride, size_t n, uint8_t* p,
                  size_t stride) {
  const double scale = c.scale, hi = c.mask;
  const int shift = c.shift;
  if (c.mask != 0) {
    for (size_t i = 0; i < n; ++i) {
      const int64_t v = Quantize(src[i * src_stride] * scale, 0.0, hi);
      p[i * stride] |= static_cast<uint8_t>(v << shift);
    }
    return;
  }
  for (size_t i = 0; i < n; ++i) {
    StoreLE<T>(p + i * stride, ToRaw<T>(src[i * src_stride] * scale));
  }
}

// A column the schema lacks: the same raw value in every record (records start zeroed).
template <typename T>
void EncodeConstant(const LasColumn& c, size_t n, uint8_t* p, size_t stride) {
  if (c.constant == 0.0) return;
  if (c.mask != 0) {
    const auto bits = static_cast<uint8_t>(Quantize(c.constant * c.scale, 0.0, c.mask) << c.shift);
    for (size_t i = 0; i < n; ++i) p[i * stride] |= bits;
    return;
  }
  const T raw = ToRaw<T>(c.constant * c.scale);
  for (size_t i = 0; i < n; ++i) StoreLE<T>(p + i * stride, raw);
}

template <typename T>
void EncodeColumn(const LasColumn& c, const PointCloud& chunk, size_t first, size_t n,
                  uint8_t* records, size_t stride) {
  uint8_t* p = records + c.offset;
  if (c.normal_axis >= 0) {
    EncodeValues<T>(c, chunk.normals[first].data() + c.normal_axis, 3, n, p, stride);
  } else if (c.scalar < 0) {
    EncodeConstant<T>(c, n, p, stride);
  } else if (chunk.scalars[c.scalar].spec.type == ScalarType::kFloat32) {
    EncodeValues<T>(c, chunk.scalars[c.scalar].f32.data() + first, 1, n, p, stride);
  } else {
    EncodeValues<T>(c, chunk.scalars[c.scalar].f64.data() + first, 1, n, p, stride);
  }
}

}  // namespace

std::vector<LasStandardColumn> LasStandardColumns(int format) {
  const LasFormatLayout layout = LasLayoutOf(format);
  std::vector<LasStandardColumn> columns;
  if (layout.extended) {
    columns.assign(std::begin(kExtendedColumns), std::end(kExtendedColumns));
  } else {
    columns.assign(std::begin(kLegacyColumns), std::end(kLegacyColumns));
  }
  if (layout.gps_offset >= 0) {
    columns.push_back({las_field::kGpsTime, LasRaw::kF64, layout.gps_offset, 0, 0});
  }
  if (layout.nir_offset >= 0) {
    columns.push_back({las_field::kNir, LasRaw::kU16, layout.nir_offset, 0, 0});
  }
  return columns;
}

LasRaw LasRawOfExtraBytesType(int data_type) {
  static constexpr LasRaw kRaws[] = {LasRaw::kU8,  LasRaw::kI8,  LasRaw::kU16, LasRaw::kI16,
                                     LasRaw::kU32, LasRaw::kI32, LasRaw::kU64, LasRaw::kI64,
                                     LasRaw::kF32, LasRaw::kF64};
  CANDI_CHECK(data_type >= 1 && data_type <= 10) << data_type;
  return kRaws[data_type - 1];
}

// Float keeps 24 bits: 32/64-bit integers and scaled values go to double.
ScalarType LasScalarTypeOf(const LasExtraBytes& e) {
  const bool small = e.data_type <= 4 || e.data_type == 9;
  return small && !e.scaled ? ScalarType::kFloat32 : ScalarType::kFloat64;
}

// A table load replaces shift, mask and int-to-float conversion; most standard attributes are
// bytes or bit fields, so this is most of the decoding work.
void FillLasByteTable(LasColumn* c) {
  if (c->raw != LasRaw::kU8 && c->raw != LasRaw::kI8) return;
  if (c->scale != 1.0 || c->add != 0.0) return;
  c->table.resize(256);
  for (int b = 0; b < 256; ++b) {
    const int v = c->raw == LasRaw::kI8 ? static_cast<int8_t>(b) : b;
    c->table[b] = static_cast<float>(c->mask != 0 ? (v >> c->shift) & c->mask : v);
  }
}

namespace {
// For a decimal scale (1/scale an integer, 0.01, 0.001 ...) and an offset that is a multiple of
// it, world = (X + offset/scale) / (1/scale) is the correctly rounded decimal: 0.001 * 3272 is
// 3.2720000000000002, 3272 / 1000 is 3.272. Returns false where that form does not apply.
bool DecimalForm(double scale, double offset, double* divisor, double* integer_offset) {
  const double inv = 1.0 / scale;
  const double rounded_inv = std::round(inv);
  if (!(rounded_inv >= 1.0 && rounded_inv < 1e12) || std::abs(inv - rounded_inv) > 1e-9 * inv) {
    return false;
  }
  const double o = offset * rounded_inv;
  const double rounded_o = std::round(o);
  if (!(std::abs(rounded_o) < 0x1p52) || std::abs(o - rounded_o) > 1e-6) return false;
  *divisor = rounded_inv;
  *integer_offset = rounded_o;
  return true;
}
}  // namespace

LasPositionDecoder::LasPositionDecoder(const Eigen::Vector3d& s, const Eigen::Vector3d& o) {
  decimal = true;
  for (int k = 0; k < 3; ++k) decimal = decimal && DecimalForm(s[k], o[k], &divisor[k], &integer_offset[k]);
  for (int k = 0; k < 3; ++k) {
    scale[k] = s[k];
    offset[k] = o[k];
  }
}

bool LasPositionDecoder::operator==(const LasPositionDecoder& o) const {
  for (int k = 0; k < 3; ++k) {
    if (scale[k] != o.scale[k] || offset[k] != o.offset[k]) return false;
  }
  return true;  // the rest follows from scale and offset
}

void DecodeLasPositions(const uint8_t* p, size_t stride, size_t n, const Eigen::Vector3d& scale,
                        const Eigen::Vector3d& offset, Eigen::Vector3d* out) {
  const LasPositionDecoder d(scale, offset);
  if (d.decimal) {
    // X + O is an exact integer below 2^53; one correctly rounded division per coordinate.
    for (size_t i = 0; i < n; ++i, p += stride) {
      out[i] = Eigen::Vector3d((LoadLE<int32_t>(p) + d.integer_offset[0]) / d.divisor[0],
                               (LoadLE<int32_t>(p + 4) + d.integer_offset[1]) / d.divisor[1],
                               (LoadLE<int32_t>(p + 8) + d.integer_offset[2]) / d.divisor[2]);
    }
    return;
  }
  for (size_t i = 0; i < n; ++i, p += stride) {
    out[i] = Eigen::Vector3d(LoadLE<int32_t>(p) * d.scale[0] + d.offset[0], LoadLE<int32_t>(p + 4) * d.scale[1] + d.offset[1],
                             LoadLE<int32_t>(p + 8) * d.scale[2] + d.offset[2]);
  }
}

void DecodeLasColors(const uint8_t* p, size_t stride, size_t n, int shift, Rgb8* out) {
  for (size_t i = 0; i < n; ++i, p += stride) {
    out[i] = Rgb8{static_cast<uint8_t>(LoadLE<uint16_t>(p) >> shift),
                  static_cast<uint8_t>(LoadLE<uint16_t>(p + 2) >> shift),
                  static_cast<uint8_t>(LoadLE<uint16_t>(p + 4) >> shift)};
  }
}

void DecodeLasColumn(const LasColumn& c, const uint8_t* records, size_t stride, size_t n,
                     size_t first, PointCloud* chunk) {
  switch (c.raw) {
    case LasRaw::kU8:
      return DecodeColumn<uint8_t>(c, records, stride, n, first, chunk);
    case LasRaw::kI8:
      return DecodeColumn<int8_t>(c, records, stride, n, first, chunk);
    case LasRaw::kU16:
      return DecodeColumn<uint16_t>(c, records, stride, n, first, chunk);
    case LasRaw::kI16:
      return DecodeColumn<int16_t>(c, records, stride, n, first, chunk);
    case LasRaw::kU32:
      return DecodeColumn<uint32_t>(c, records, stride, n, first, chunk);
    case LasRaw::kI32:
      return DecodeColumn<int32_t>(c, records, stride, n, first, chunk);
    case LasRaw::kU64:
      return DecodeColumn<uint64_t>(c, records, stride, n, first, chunk);
    case LasRaw::kI64:
      return DecodeColumn<int64_t>(c, records, stride, n, first, chunk);
    case LasRaw::kF32:
      return DecodeColumn<float>(c, records, stride, n, first, chunk);
    case LasRaw::kF64:
      return DecodeColumn<double>(c, records, stride, n, first, chunk);
  }
}

void EncodeLasColumn(const LasColumn& c, const PointCloud& chunk, size_t first, size_t n,
                     uint8_t* records, size_t stride) {
  switch (c.raw) {
    case LasRaw::kU8:
      return EncodeColumn<uint8_t>(c, chunk, first, n, records, stride);
    case LasRaw::kI8:
      return EncodeColumn<int8_t>(c, chunk, first, n, records, stride);
    case LasRaw::kU16:
      return EncodeColumn<uint16_t>(c, chunk, first, n, records, stride);
    case LasRaw::kI16:
      return EncodeColumn<int16_t>(c, chunk, first, n, records, stride);
    case LasRaw::kF32:
      return EncodeColumn<float>(c, chunk, first, n, records, stride);
    case LasRaw::kF64:
      return EncodeColumn<double>(c, chunk, first, n, records, stride);
    default:
      CANDI_CHECK(false) << "the LAS writer does not encode raw type " << int(c.raw);
  }
}

// One axis per pass keeps the bounds in registers (with the three axes in one loop they are
// spilled to memory, since the byte stores may alias anything).
size_t EncodeLasPositions(const Eigen::Vector3d* positions, size_t n, const Eigen::Vector3d& origin,
                          const Eigen::Vector3d& offset, const Eigen::Vector3d& scale, uint8_t* out,
                          size_t stride, int32_t* lo, int32_t* hi) {
  // Multiplying by the inverse instead of dividing: the quotient of a coordinate that came from
  // X * scale + offset differs from X by a few ulps either way, so the rounding is the same.
  // All three axes in one pass over the points (a runtime axis index defeats the compiler).
  const double o[3] = {origin.x(), origin.y(), origin.z()};
  const double f[3] = {offset.x(), offset.y(), offset.z()};
  const double inv[3] = {1.0 / scale.x(), 1.0 / scale.y(), 1.0 / scale.z()};
  int32_t a[3] = {lo[0], lo[1], lo[2]}, b[3] = {hi[0], hi[1], hi[2]};
  for (size_t i = 0; i < n; ++i) {
    const double* p = positions[i].data();
    int32_t x[3];
    for (int k = 0; k < 3; ++k) {
      const double q = ((p[k] + o[k]) - f[k]) * inv[k];
      if (!(q > -2147483648.5 && q < 2147483647.5)) return i;  // also NaN
      x[k] = static_cast<int32_t>(q + std::copysign(0.5, q));
      a[k] = std::min(a[k], x[k]);
      b[k] = std::max(b[k], x[k]);
    }
    std::memcpy(out + i * stride, x, sizeof(x));
  }
  for (int k = 0; k < 3; ++k) {
    lo[k] = a[k];
    hi[k] = b[k];
  }
  return n;
}

}  // namespace candi::io
