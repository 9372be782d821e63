#include "io/point_records.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel.h"

namespace candi::io {

std::optional<Box3d> RecordBounds(const MappedFile& map, const PointRecordLayout& l) {
  if (!HoldsRecords(map, l)) return std::nullopt;
  constexpr size_t kBlock = size_t{1} << 16;
  const size_t n = static_cast<size_t>(l.count), blocks = (n + kBlock - 1) / kBlock;
  std::vector<Box3d> boxes(blocks);
  std::vector<char> finite(blocks, 1);
  const uint8_t* records = map.data() + l.first_byte;
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    const size_t first = b * kBlock, m = std::min(kBlock, n - first);
    Box3d box;
    bool ok = true;
    ForEachRecord(l, records + first * l.stride, m, 0, [&](size_t, const Eigen::Vector3d& p, uint32_t) {
      ok &= std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z());
      box.Extend(p);
    });
    boxes[b] = box;
    finite[b] = ok;
  });
  Box3d total;
  for (size_t b = 0; b < blocks; ++b) {
    if (!finite[b]) return std::nullopt;
    total.Extend(boxes[b]);
  }
  return total;
}

}  // namespace candi::io
