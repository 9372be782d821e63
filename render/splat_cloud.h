// SplatCloud: points prepared for SPBR, held in memory at 10 bytes per point copy.
//
// Built once per (clouds, repeat level L, seed): every point gets its ensemble from a seeded hash
// of its index (its position in the inputs, concatenated), a point with multiplicity m (opacity
// control's `spbr_multiplicity`) goes to m distinct ensembles (a random m-subset, see
// ForEachEnsemble), the copies are grouped by ensemble and, within an ensemble, kept in Morton order, so
// each ensemble is a random and spatially coherent subset. Each ensemble is cut into blocks of
// consecutive points; a block stores its points as 16-bit coordinates on its own bounding box
// (error <= extent / 131070 per axis, documented per block by `step`), plus the colour packed
// as 0x00RRGGBB: 10 bytes per point copy.
// Positions are relative to `frame`, the world origin rounded to whole metres at the data's
// centre: a cloud and the same cloud shifted by whole metres give the same SplatCloud.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/box.h"
#include "core/local_frame.h"
#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/spbr_settings.h"

namespace candi::render {

struct SplatCloudOptions {
  // L and the seed of every point's ensemble; opaque: one ensemble, multiplicities ignored; the
  // point size the cloud is drawn with (RenderSpbr).
  SpbrSettings spbr;
  // Points per block, in [64, 65536]; 0: each ensemble in ~1024 blocks (64..4096 points), so a
  // block covers a small part of the image and is drawn by one or two bands of rows.
  int block_size = 0;
  bool use_multiplicity = true;  // honour the `spbr_multiplicity` field when present (not opaque)
  Rgb8 default_color{200, 200, 200};  // for clouds without colours
  void Check() const;
};

inline constexpr const char* kMultiplicityField = "spbr_multiplicity";

struct SplatBlock {
  float origin[3];  // position of grid point (0, 0, 0), render frame, m
  float step[3];    // grid spacing per axis, m (0 on a flat axis)
  float lo[3], hi[3];  // bounding box of the block's points, render frame, m
  uint64_t begin;   // first point in the SplatCloud arrays
  uint32_t count;
};

// A std::allocator that leaves trivially constructible elements uninitialized (no zero fill):
// arrays that are written in full right after they are sized.
// Large arrays (>= kLargeArrayBytes) are 2 MiB aligned and asked of the kernel as huge pages
// (transparent huge pages, where the system allows them): a fresh 10^8-entry array then costs a
// page fault per 2 MiB instead of per 4 KiB.
inline constexpr size_t kLargeArrayBytes = size_t{32} << 20;
void* AllocateLargeArray(size_t bytes);  // throws std::bad_alloc
void FreeLargeArray(void* p);

template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  using std::allocator<T>::allocator;
  T* allocate(size_t n) {
    if (n * sizeof(T) >= kLargeArrayBytes) return static_cast<T*>(AllocateLargeArray(n * sizeof(T)));
    return std::allocator<T>::allocate(n);
  }
  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) >= kLargeArrayBytes) return FreeLargeArray(p);
    std::allocator<T>::deallocate(p, n);
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0) ::new (static_cast<void*>(p)) U;
    else ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <typename T>
using UninitVector = std::vector<T, DefaultInitAllocator<T>>;

struct SplatCloud {
  int repeat_level = 1;  // the ensembles of the arrays (SpbrSettings::EffectiveRepeatLevel)
  uint64_t seed = 0;
  double point_size = 1.0;    // pixels, as drawn (the settings' point size)
  LocalFrame frame;           // world = position + frame.origin
  Box3d bounds;               // of all points, render frame
  uint64_t source_points = 0; // points in the inputs (multiplicity 0 included)
  UninitVector<uint16_t> qx, qy, qz;  // one entry per point copy
  UninitVector<uint32_t> colors;             // 0x00RRGGBB
  std::vector<SplatBlock> blocks;           // ensemble by ensemble
  std::vector<uint64_t> ensemble_blocks;    // L + 1 offsets into blocks

  uint64_t copies() const { return colors.size(); }
  size_t MemoryBytes() const;  // bytes held (arrays' capacities)
};

inline uint32_t PackColor(Rgb8 c) {
  return static_cast<uint32_t>(c.r) << 16 | static_cast<uint32_t>(c.g) << 8 | c.b;
}

// The ensemble of point `index` under `seed`, in [0, L): the high bits of a seeded hash scaled
// by L (Lemire's multiply-shift), independent of threads and chunking.
inline int EnsembleOfHash(uint64_t hash, int repeat_level) {
  return static_cast<int>(((hash >> 32) * static_cast<uint64_t>(repeat_level)) >> 32);
}
inline int EnsembleOf(uint64_t seed, uint64_t index, int repeat_level) {
  return EnsembleOfHash(HashIndex(seed, index), repeat_level);
}

// Calls f(e) for each ensemble of point `index` when it has m copies (m clamped to [0, L]):
// m = 1 gives EnsembleOf; m >= L every ensemble; otherwise a uniformly random m-subset of [0, L)
// drawn with Floyd's algorithm from a seeded hash of (index, step), in no particular order. For
// m > L / 2 the L - m ensembles left out are drawn instead (the complement of a uniform subset is
// uniform), so a point costs min(m, L - m) hashes.
// Random subsets matter: with consecutive ensembles (e0, e0+1, ...) two points' copies would
// overlap by a random fraction that does not shrink as L grows, leaving an image error that more
// ensembles never remove; random subsets overlap as independent draws do. Uses a thread-local
// bitset of L bits.
template <typename F>
void ForEachEnsemble(uint64_t seed, uint64_t index, int m, int repeat_level, F&& f) {
  const int L = repeat_level;
  if (m <= 0) return;
  if (m == 1) {
    f(EnsembleOf(seed, index, L));
    return;
  }
  if (m >= L) {
    for (int e = 0; e < L; ++e) f(e);
    return;
  }
  thread_local std::vector<uint64_t> taken;
  if (taken.size() < static_cast<size_t>(L + 63) / 64) taken.assign((L + 63) / 64, 0);
  thread_local std::vector<int> chosen;
  chosen.clear();
  const bool complement = 2 * m > L;
  const int draw = complement ? L - m : m;
  const uint64_t stream = HashIndex(seed, index, 0x5e1ec7);
  for (int j = L - draw; j < L; ++j) {
    const uint64_t h = Mix64(stream ^ static_cast<uint64_t>(j));
    const int t = static_cast<int>(((h >> 32) * static_cast<uint64_t>(j + 1)) >> 32);  // [0, j]
    const int e = (taken[t >> 6] >> (t & 63)) & 1 ? j : t;
    taken[e >> 6] |= uint64_t{1} << (e & 63);
    chosen.push_back(e);
  }
  if (complement) {
    for (int e = 0; e < L; ++e)
      if (!((taken[e >> 6] >> (e & 63)) & 1)) f(e);
    for (int e : chosen) taken[e >> 6] &= ~(uint64_t{1} << (e & 63));
    return;
  }
  for (int e : chosen) {
    taken[e >> 6] &= ~(uint64_t{1} << (e & 63));
    f(e);
  }
}

// Builds the SplatCloud of the given clouds (any frames; NaN positions are refused with
// InputError). Throws InternalError for more than 2^32 points (render those by streaming).
SplatCloud BuildSplatCloud(const SplatCloudOptions& options,
                           const std::vector<const PointCloud*>& clouds,
                           const ProgressCallback& progress = nullptr);

// The render frame candi uses for data spanning `world`: origin at the centre, rounded to metres.
LocalFrame RenderFrameFor(const Box3d& world);

}  // namespace candi::render
