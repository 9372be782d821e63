#include "render/pack_records.h"

#include "core/simd.h"

namespace candi::render::pack_internal {

namespace {

template <typename P>
inline void EncodeRun(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const P* points, size_t n,
                      uint64_t* words) {
  for (size_t i = 0; i < n; ++i) words[i] = q.Encode(points[i].Position(shift), points[i].rgb);
}

}  // namespace

CANDI_TARGET_CLONES_AVX2
void Encode(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const WidePoint* points, size_t n,
            uint64_t* words) {
  EncodeRun(q, shift, points, n, words);
}

CANDI_TARGET_CLONES_AVX2
void Encode(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const CompactPoint* points, size_t n,
            uint64_t* words) {
  EncodeRun(q, shift, points, n, words);
}

}  // namespace candi::render::pack_internal
