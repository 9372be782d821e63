#include "render/splat_cloud.h"

#include <sys/mman.h>
#include <tbb/blocked_range.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::render {

void SplatCloudOptions::Check() const {
  spbr.Check();
  CANDI_CHECK_OPTION(block_size == 0 || (block_size >= 64 && block_size <= 65536), block_size,
                     "0 (automatic) or in [64, 65536]");
}

void* AllocateLargeArray(size_t bytes) {
  constexpr size_t kHugePage = size_t{2} << 20;
  const size_t rounded = (bytes + kHugePage - 1) / kHugePage * kHugePage;
  void* p = std::aligned_alloc(kHugePage, rounded);
  if (p == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(p, rounded, MADV_HUGEPAGE);  // advice: refused or ignored, the memory is the same
#endif
  return p;
}

void FreeLargeArray(void* p) { std::free(p); }

size_t SplatCloud::MemoryBytes() const {
  return (qx.capacity() + qy.capacity() + qz.capacity()) * sizeof(uint16_t) +
         colors.capacity() * sizeof(uint32_t) + blocks.capacity() * sizeof(SplatBlock) +
         ensemble_blocks.capacity() * sizeof(uint64_t);
}

LocalFrame RenderFrameFor(const Box3d& world) {
  LocalFrame frame;
  if (world.IsEmpty()) return frame;
  const Eigen::Vector3d c = world.Center();
  for (int k = 0; k < 3; ++k) frame.origin[k] = std::round(c[k]);
  return frame;
}

namespace {

// One input point, located: which cloud, which point in it.
struct Source {
  const PointCloud* cloud;
  uint64_t first;  // global index of its first point
  Eigen::Vector3d shift;  // cloud frame origin - render frame origin (exact for whole metres)
  const ScalarField* multiplicity;
};

// Spreads the low 10 bits of v to every third bit.
inline uint32_t Spread3(uint32_t v) {
  v &= 0x3ffu;
  v = (v | (v << 16)) & 0x030000ffu;
  v = (v | (v << 8)) & 0x0300f00fu;
  v = (v | (v << 4)) & 0x030c30c3u;
  v = (v | (v << 2)) & 0x09249249u;
  return v;
}

// 30-bit Morton code of a position on a 1024^3 grid over `box` (x in the highest bit of each
// triple).
inline uint32_t Morton30(const Eigen::Vector3f& p, const Eigen::Vector3f& lo, const Eigen::Vector3f& inv_cell) {
  uint32_t cell[3];
  for (int k = 0; k < 3; ++k) {
    const float t = (p[k] - lo[k]) * inv_cell[k];
    cell[k] = static_cast<uint32_t>(std::clamp(t, 0.0f, 1023.0f));
  }
  return Spread3(cell[0]) << 2 | Spread3(cell[1]) << 1 | Spread3(cell[2]);
}

// A point while the splat cloud is built.
struct PointRecord {
  uint32_t code;   // Morton30 in the render frame's bounds
  uint32_t index;  // in the input (the ensemble hash's)
  Eigen::Vector3f position;
  Rgb8 color;
  uint16_t multiplicity;
};

// Stable counting scatter of in[begin, end) into out[begin, end) by the 10-bit digit at `shift`.
void ScatterByDigit(const PointRecord* in, PointRecord* out, size_t begin, size_t end, int shift) {
  uint32_t count[1024] = {};
  for (size_t i = begin; i < end; ++i) ++count[(in[i].code >> shift) & 1023u];
  size_t at = begin;
  for (uint32_t& c : count) {
    const uint32_t k = c;
    c = static_cast<uint32_t>(at - begin);
    at += k;
  }
  for (size_t i = begin; i < end; ++i) out[begin + count[(in[i].code >> shift) & 1023u]++] = in[i];
}

// Sorts the records by code (30 bits), stably. First a counting scatter on the top 10 bits: each
// pass counts the digits of consecutive parts of the input in parallel, then scatters each part
// after the same digits of the parts before it (the serial result on any thread count). Then each
// of the 1,024 buckets, small enough for the cache, is sorted on its own by two LSD passes over
// the low 20 bits, buckets in parallel. A stable partition followed by stable sorts of its parts
// is the stable sort (the order of a full LSD sort), with one pass over memory instead of three.
void SortByCode(UninitVector<PointRecord>* records) {
  const size_t n = records->size();
  constexpr int kBits = 10;
  constexpr size_t kDigits = size_t{1} << kBits;
  const size_t parts = std::clamp<size_t>(n / 65536, 1, 64);
  const size_t per_part = (n + parts - 1) / parts;
  UninitVector<PointRecord> other(n);
  std::vector<uint64_t> offset(parts * kDigits, 0);
  const PointRecord* in = records->data();
  PointRecord* out = other.data();
  constexpr int kTop = 20;
  ParallelFor(size_t{0}, parts, [&](size_t p) {
    uint64_t* count = offset.data() + p * kDigits;
    for (size_t i = p * per_part; i < std::min(n, (p + 1) * per_part); ++i) ++count[in[i].code >> kTop];
  });
  std::vector<uint64_t> bucket(kDigits + 1, 0);
  uint64_t at = 0;
  for (size_t d = 0; d < kDigits; ++d) {
    bucket[d] = at;
    for (size_t p = 0; p < parts; ++p) {
      const uint64_t c = offset[p * kDigits + d];
      offset[p * kDigits + d] = at;
      at += c;
    }
  }
  bucket[kDigits] = at;
  ParallelFor(size_t{0}, parts, [&](size_t p) {
    uint64_t* fill = offset.data() + p * kDigits;
    for (size_t i = p * per_part; i < std::min(n, (p + 1) * per_part); ++i) out[fill[in[i].code >> kTop]++] = in[i];
  });
  // Each bucket: digit 0 from `other` into `records`, digit 1 back into `other`.
  PointRecord* a = records->data();
  ParallelFor(size_t{0}, kDigits, [&](size_t d) {
    ScatterByDigit(out, a, bucket[d], bucket[d + 1], 0);
    ScatterByDigit(a, out, bucket[d], bucket[d + 1], kBits);
  });
  records->swap(other);
}

// The records of points drawn once (their `index` holding their ensemble, not their input
// index), put in copy order: grouped by ensemble, within an ensemble by code, ties in input
// order. A stable counting scatter by ensemble (parts counted and scattered in parallel, each
// after the same ensembles of the parts before it, so any thread count gives the serial result),
// then each ensemble, in parallel, by three stable 10-bit passes over its code: the order the
// Morton sort followed by the counting sort by ensemble gives, without the passes over every
// point between them. start[e] is where ensemble e begins (start[L]: the total).
void GroupByEnsembleThenCode(UninitVector<PointRecord>* records, int L, std::vector<uint64_t>* start) {
  const size_t n = records->size();
  const size_t parts = std::clamp<size_t>(n / 65536, 1, std::max<size_t>(1, (size_t{1} << 22) / L));
  const size_t per_part = (n + parts - 1) / parts;
  std::vector<uint64_t> offset(parts * static_cast<size_t>(L), 0);
  UninitVector<PointRecord> other(n);
  const PointRecord* in = records->data();
  ParallelFor(size_t{0}, parts, [&](size_t p) {
    uint64_t* count = offset.data() + p * L;
    for (size_t i = p * per_part; i < std::min(n, (p + 1) * per_part); ++i) ++count[in[i].index];
  });
  start->assign(L + 1, 0);
  uint64_t at = 0;
  for (int e = 0; e < L; ++e) {
    (*start)[e] = at;
    for (size_t p = 0; p < parts; ++p) {
      const uint64_t c = offset[p * L + e];
      offset[p * L + e] = at;
      at += c;
    }
  }
  (*start)[L] = at;
  PointRecord* grouped = other.data();
  ParallelFor(size_t{0}, parts, [&](size_t p) {
    uint64_t* fill = offset.data() + p * L;
    for (size_t i = p * per_part; i < std::min(n, (p + 1) * per_part); ++i) grouped[fill[in[i].index]++] = in[i];
  });
  PointRecord* a = records->data();
  ParallelFor(size_t{0}, static_cast<size_t>(L), [&](size_t e) {
    const size_t begin = (*start)[e], end = (*start)[e + 1];
    ScatterByDigit(grouped, a, begin, end, 0);
    ScatterByDigit(a, grouped, begin, end, 10);
    ScatterByDigit(grouped, a, begin, end, 20);
  });
}

// Each copy's position and colour, in copy order.
struct Copies {
  UninitVector<Eigen::Vector3f> position;
  UninitVector<Rgb8> color;
};

// The copies of records in Morton order (records[k].index: the input index; multiplicity m: m
// ensembles, ForEachEnsemble) per ensemble (a counting sort); within an ensemble, Morton order.
// The Morton ranks are cut into chunks counted and filled in parallel: chunk c's copies of
// ensemble e go after those of chunks 0..c-1, so the result does not depend on the thread count.
// The chunk count is capped so that the chunks x L counters stay small for large L.
Copies CopiesByEnsemble(uint64_t seed, int L, const UninitVector<PointRecord>& records, std::vector<uint64_t>* start) {
  const size_t n = records.size();
  const size_t chunks = std::clamp<size_t>(n / 65536, 1, std::max<size_t>(1, (size_t{1} << 22) / L));
  const size_t per_chunk = (n + chunks - 1) / chunks;
  std::vector<uint64_t> offset(chunks * static_cast<size_t>(L), 0);  // counts, then fill positions
  // A point drawn once has its ensemble hashed on the count and kept for the fill.
  UninitVector<uint32_t> single(n);
  auto for_each_copy = [&](size_t c, bool counting, auto&& f) {
    const size_t end = std::min(n, (c + 1) * per_chunk);
    for (size_t k = c * per_chunk; k < end; ++k) {
      const int m = records[k].multiplicity;
      if (m == 1) {
        if (counting) single[k] = static_cast<uint32_t>(EnsembleOf(seed, records[k].index, L));
        f(static_cast<int>(single[k]), k);
      } else {
        ForEachEnsemble(seed, records[k].index, m, L, [&](int e) { f(e, k); });
      }
    }
  };
  ParallelFor(size_t{0}, chunks, [&](size_t c) {
    uint64_t* count = offset.data() + c * L;
    for_each_copy(c, true, [&](int e, size_t) { ++count[e]; });
  });
  start->assign(L + 1, 0);
  for (int e = 0; e < L; ++e) {
    uint64_t at = (*start)[e];
    for (size_t c = 0; c < chunks; ++c) {
      const uint64_t count = offset[c * L + e];
      offset[c * L + e] = at;
      at += count;
    }
    (*start)[e + 1] = at;
  }
  Copies copies;
  copies.position.resize((*start)[L]);
  copies.color.resize((*start)[L]);
  ParallelFor(size_t{0}, chunks, [&](size_t c) {
    uint64_t* fill = offset.data() + c * L;
    for_each_copy(c, false, [&](int e, size_t k) {
      const uint64_t at = fill[e]++;
      copies.position[at] = records[k].position;
      copies.color[at] = records[k].color;
    });
  });
  return copies;
}

// Quantizes each of out->blocks on its own bounding box: copy c's position_of(c) and colour_of(c)
// into out's arrays.
template <typename PositionOf, typename ColourOf>
void Quantize(const PositionOf& position_of, const ColourOf& colour_of, SplatCloud* out) {
  ParallelFor(size_t{0}, out->blocks.size(), [&](size_t k) {
    SplatBlock& block = out->blocks[k];
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (uint64_t c = block.begin; c < block.begin + block.count; ++c) {
      const Eigen::Vector3f& p = position_of(c);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], p[a]);
        hi[a] = std::max(hi[a], p[a]);
      }
    }
    float inv[3];
    for (int a = 0; a < 3; ++a) {
      block.origin[a] = block.lo[a] = lo[a];
      block.hi[a] = hi[a];
      block.step[a] = (hi[a] - lo[a]) / 65535.0f;
      inv[a] = block.step[a] > 0 ? 1.0f / block.step[a] : 0.0f;
    }
    for (uint64_t c = block.begin; c < block.begin + block.count; ++c) {
      const Eigen::Vector3f& p = position_of(c);
      // (p - lo) * inv is in [0, 65535] up to rounding: round half up by truncation.
      const auto q = [&](int a) {
        return static_cast<uint16_t>(std::min((p[a] - lo[a]) * inv[a] + 0.5f, 65535.0f));
      };
      out->qx[c] = q(0);
      out->qy[c] = q(1);
      out->qz[c] = q(2);
      out->colors[c] = PackColor(colour_of(c));
    }
  });
}

struct Located {
  std::vector<Source> sources;
  uint64_t total = 0;
};

Located Locate(const std::vector<const PointCloud*>& clouds, const LocalFrame& frame) {
  Located l;
  for (const PointCloud* c : clouds) {
    CANDI_CHECK(c != nullptr);
    c->CheckConsistent();
    l.sources.push_back({c, l.total, c->frame.origin - frame.origin, c->FindScalar(kMultiplicityField)});
    l.total += c->size();
  }
  CANDI_CHECK(l.total < (uint64_t{1} << 32))
      << l.total << " points: an in-memory SplatCloud holds < 2^32; render larger data by streaming";
  return l;
}

}  // namespace

SplatCloud BuildSplatCloud(const SplatCloudOptions& options,
                           const std::vector<const PointCloud*>& clouds,
                           const ProgressCallback& progress) {
  options.Check();
  std::vector<Box3d> local_bounds;  // of each cloud, in its frame
  Box3d world;
  for (const PointCloud* c : clouds) {
    local_bounds.push_back(c->LocalBounds());
    world.Extend(local_bounds.back().Translated(c->frame.origin));
  }
  SplatCloud out;
  out.repeat_level = options.spbr.EffectiveRepeatLevel();
  out.seed = options.spbr.seed;
  out.point_size = options.spbr.point_size;
  out.frame = RenderFrameFor(world);
  const Located located = Locate(clouds, out.frame);
  out.source_points = located.total;
  const size_t n = located.total;

  for (size_t k = 0; k < located.sources.size(); ++k) {
    const Source& s = located.sources[k];
    if (!s.cloud->empty()) out.bounds.Extend(local_bounds[k].Translated(s.shift));
  }
  // Each point as a record: its Morton code, input index, position in the render frame, colour
  // and multiplicity (in parallel); NaN is an error naming the first bad point whatever the
  // thread count.
  UninitVector<PointRecord> records(n);
  const Eigen::Vector3f lo = out.bounds.min.cast<float>();
  const Eigen::Vector3f inv_cell = (1024.0 / out.bounds.Extent().array().max(1e-9)).matrix().cast<float>();
  const int L = out.repeat_level;
  const double cap = std::min(L, 65535);  // more copies than ensembles add nothing
  const bool use_multiplicity = options.use_multiplicity && !options.spbr.opaque;
  // Every point drawn once (no multiplicities): the records carry their ensembles and are put in
  // copy order directly (GroupByEnsembleThenCode).
  const bool single_copies =
      L > 1 && std::none_of(located.sources.begin(), located.sources.end(), [&](const Source& s) {
        return use_multiplicity && s.multiplicity != nullptr;
      });
  std::atomic<uint64_t> first_bad{std::numeric_limits<uint64_t>::max()};
  for (const Source& s : located.sources) {
    const PointCloud& c = *s.cloud;
    const bool weights = use_multiplicity && s.multiplicity != nullptr;
    ParallelFor(tbb::blocked_range<size_t>(0, c.size(), 65536), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const Eigen::Vector3d p = c.positions[i] + s.shift;
        if (!p.allFinite()) {
          uint64_t bad = first_bad.load();
          while (s.first + i < bad && !first_bad.compare_exchange_weak(bad, s.first + i)) {}
        }
        PointRecord& rec = records[s.first + i];
        rec.position = p.cast<float>();
        rec.code = Morton30(rec.position, lo, inv_cell);
        rec.index = single_copies
                        ? static_cast<uint32_t>(EnsembleOf(options.spbr.seed, s.first + i, L))
                        : static_cast<uint32_t>(s.first + i);
        rec.color = c.schema.colors ? c.colors[i] : options.default_color;
        rec.multiplicity = 1;
        if (weights) {
          const double m = s.multiplicity->Get(i);
          rec.multiplicity = static_cast<uint16_t>(std::isfinite(m) ? std::clamp(std::round(m), 0.0, cap) : 0.0);
        }
      }
    });
  }
  if (first_bad.load() != std::numeric_limits<uint64_t>::max()) {
    throw InputError("point " + std::to_string(first_bad.load()) + " of the render input has a NaN or "
                     "infinite coordinate");
  }
  if (progress) progress(n / 4, n);
  std::vector<uint64_t> start;  // where each ensemble's copies begin
  Copies copies;
  if (single_copies) {
    GroupByEnsembleThenCode(&records, L, &start);
  } else {
    SortByCode(&records);  // records[k].index stays the input index, which the ensemble hash uses
    copies = CopiesByEnsemble(options.spbr.seed, L, records, &start);
    UninitVector<PointRecord>().swap(records);
  }
  if (progress) progress(n / 2, n);

  // Blocks: cut each ensemble, quantize each block on its own bounding box.
  const uint64_t count = start[L];
  out.ensemble_blocks.assign(L + 1, 0);
  const uint64_t block_size =
      options.block_size > 0 ? options.block_size : std::clamp<uint64_t>(count / L / 1024, 64, 4096);
  for (int e = 0; e < L; ++e) {
    for (uint64_t b = start[e]; b < start[e + 1]; b += block_size) {
      SplatBlock block{};
      block.begin = b;
      block.count = static_cast<uint32_t>(std::min<uint64_t>(block_size, start[e + 1] - b));
      out.blocks.push_back(block);
    }
    out.ensemble_blocks[e + 1] = out.blocks.size();
  }
  out.qx.resize(count);
  out.qy.resize(count);
  out.qz.resize(count);
  out.colors.resize(count);
  if (single_copies) {
    Quantize([&](uint64_t c) -> const Eigen::Vector3f& { return records[c].position; },
             [&](uint64_t c) { return records[c].color; }, &out);
  } else {
    Quantize([&](uint64_t c) -> const Eigen::Vector3f& { return copies.position[c]; },
             [&](uint64_t c) { return copies.color[c]; }, &out);
  }
  if (progress) progress(n, n);
  return out;
}

}  // namespace candi::render
