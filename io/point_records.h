// Point records read in place (io/point_file.h's PointRecordLayout): positions as Read() gives
// them and colours packed, decoded straight from a mapped file by whoever holds its bytes, in
// parallel blocks. For consumers that need only positions and colours (the streaming renderer):
// the reader's chunk, a copy of every point, is skipped.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>

#include <Eigen/Core>

#include "core/binary_file.h"
#include "core/box.h"
#include "core/mapped_file.h"
#include "io/las/las_columns.h"
#include "io/point_file.h"

namespace candi::io {

// Calls f(i, position, rgb) for records i in [0, n) at `records`, in order: the position in the
// reader's frame as Read() gives it (the same doubles), the colour as 0x00RRGGBB as Read() gives
// it (`fallback` when the layout has none).
template <typename F>
void ForEachRecord(const PointRecordLayout& l, const uint8_t* records, size_t n, uint32_t fallback, F&& f);

// Whether `map` holds all of the layout's records (a file cut short does not; its reader says
// where).
inline bool HoldsRecords(const MappedFile& map, const PointRecordLayout& l) {
  return map.size() >= l.first_byte && (map.size() - l.first_byte) / (l.stride ? l.stride : 1) >= l.count;
}

// The box of the file's records in the reader's frame (empty for no records), read by parallel
// blocks: the same doubles as a point-by-point pass over Read()'s chunks. nullopt when a
// coordinate is NaN or infinite (the reader refuses that file, saying which point) or the file
// does not hold its records.
std::optional<Box3d> RecordBounds(const MappedFile& map, const PointRecordLayout& l);

// ---- implementation ----

namespace records_internal {

template <typename T>
inline T Load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

template <PointRecordLayout::Coordinates C, typename F>
inline void ForEachRecordAs(const PointRecordLayout& l, const uint8_t* records, size_t n, uint32_t fallback, F&& f) {
  using Coordinates = PointRecordLayout::Coordinates;
  const LasPositionDecoder las = C == Coordinates::kLasInt32 ? LasPositionDecoder(l.scale, l.offset) : LasPositionDecoder();
  const size_t x = l.xyz[0], y = l.xyz[1], z = l.xyz[2];
  const bool colour = l.rgb[0] >= 0;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* r = records + i * l.stride;
    Eigen::Vector3d p;
    if constexpr (C == Coordinates::kFloat32) {
      p = Eigen::Vector3d(Load<float>(r + x), Load<float>(r + y), Load<float>(r + z));
    } else if constexpr (C == Coordinates::kFloat64) {
      p = Eigen::Vector3d(Load<double>(r + x), Load<double>(r + y), Load<double>(r + z));
    } else {
      p = Eigen::Vector3d(las.Axis(0, Load<int32_t>(r + x)), las.Axis(1, Load<int32_t>(r + y)),
                          las.Axis(2, Load<int32_t>(r + z)));
    }
    uint32_t rgb = fallback;
    if (colour) {
      if (l.color_bytes == 1) {
        rgb = uint32_t{r[l.rgb[0]]} << 16 | uint32_t{r[l.rgb[1]]} << 8 | uint32_t{r[l.rgb[2]]};
      } else {
        auto channel = [&](int c) { return uint32_t{static_cast<uint8_t>(LoadLE<uint16_t>(r + l.rgb[c]) >> l.color_shift)}; };
        rgb = channel(0) << 16 | channel(1) << 8 | channel(2);
      }
    }
    f(i, p, rgb);
  }
}

}  // namespace records_internal

template <typename F>
void ForEachRecord(const PointRecordLayout& l, const uint8_t* records, size_t n, uint32_t fallback, F&& f) {
  using Coordinates = PointRecordLayout::Coordinates;
  switch (l.coordinates) {
    case Coordinates::kFloat32:
      return records_internal::ForEachRecordAs<Coordinates::kFloat32>(l, records, n, fallback, f);
    case Coordinates::kFloat64:
      return records_internal::ForEachRecordAs<Coordinates::kFloat64>(l, records, n, fallback, f);
    case Coordinates::kLasInt32:
      return records_internal::ForEachRecordAs<Coordinates::kLasInt32>(l, records, n, fallback, f);
  }
}

}  // namespace candi::io
