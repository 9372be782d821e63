#include "sampling/surface_sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "core/check.h"
#include "core/parallel.h"
#include "core/rng.h"

namespace candi::sampling {

namespace {

constexpr size_t kGrain = 16384;

// Walker's alias table (Vose's construction): O(1) draws from a discrete distribution.
// Built serially in index order, so it is the same on every run. One 8-byte entry per column, so
// a draw reads one cache line: column i is kept when a 32-bit uniform is below keep (a column
// that is always kept has alias i, so either outcome is i).
struct AliasTable {
  struct Entry {
    uint32_t keep;   // probability of keeping column i, x 2^32
    uint32_t alias;  // the other outcome of column i
  };
  std::vector<Entry> entries;

  explicit AliasTable(const std::vector<double>& weights) : entries(weights.size()) {
    const size_t n = weights.size();
    const double total = std::accumulate(weights.begin(), weights.end(), 0.0);
    std::vector<double> scaled(n);
    std::vector<uint32_t> small, large;
    for (size_t i = 0; i < n; ++i) {
      scaled[i] = weights[i] * static_cast<double>(n) / total;
      entries[i] = {0xffffffffu, static_cast<uint32_t>(i)};
      (scaled[i] < 1 ? small : large).push_back(static_cast<uint32_t>(i));
    }
    while (!small.empty() && !large.empty()) {
      const uint32_t s = small.back(), l = large.back();
      small.pop_back();
      entries[s] = {static_cast<uint32_t>(std::min(scaled[s] * 0x1.0p32, 4294967295.0)), l};
      scaled[l] += scaled[s] - 1;
      if (scaled[l] < 1) {
        large.pop_back();
        small.push_back(l);
      }
    }
  }

  // The column from the high 32 bits (multiply-shift), the keep test from the low 32.
  size_t Column(uint64_t h) const { return static_cast<size_t>(((h >> 32) * entries.size()) >> 32); }
  uint32_t Outcome(size_t column, uint64_t h) const {
    const Entry& e = entries[column];
    return static_cast<uint32_t>(h) < e.keep ? static_cast<uint32_t>(column) : e.alias;
  }
};

// Draws samples [begin, end) from `table` and adds one to per_face[triangle] for each (atomic,
// so the sums, and the output, do not depend on the thread count). The table and the counts are
// megabytes read at random: draws go in batches whose table entries and counters are prefetched
// first, so the cache misses overlap.
template <typename Count>
void CountDraws(const AliasTable& table, uint64_t seed, size_t begin, size_t end, Count* per_face) {
  constexpr size_t kBatch = 32;
  uint64_t hash[kBatch];
  size_t column[kBatch];
  uint32_t face[kBatch];
  for (size_t k0 = begin; k0 < end; k0 += kBatch) {
    const size_t n = std::min(kBatch, end - k0);
    for (size_t b = 0; b < n; ++b) {
      hash[b] = HashIndex(seed, k0 + b, 0);
      column[b] = table.Column(hash[b]);
      __builtin_prefetch(&table.entries[column[b]]);
    }
    for (size_t b = 0; b < n; ++b) {
      face[b] = table.Outcome(column[b], hash[b]);
      __builtin_prefetch(&per_face[face[b]], 1);
    }
    for (size_t b = 0; b < n; ++b) __atomic_fetch_add(&per_face[face[b]], Count{1}, __ATOMIC_RELAXED);
  }
}

template <typename Body>
void ParallelBlocks(int threads, size_t n, const Body& body) {
  auto run = [&] {
    ParallelFor(tbb::blocked_range<size_t>(0, n, kGrain),
                      [&](const tbb::blocked_range<size_t>& r) { body(r.begin(), r.end()); });
  };
  if (threads > 0) {
    tbb::task_arena(threads).execute(run);
  } else {
    run();
  }
}

std::vector<double> TriangleAreas(const TriMesh& mesh, int threads) {
  std::vector<double> areas(mesh.faces.size());
  const auto& p = mesh.vertices.positions;
  ParallelBlocks(threads, areas.size(), [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) {
      const auto& t = mesh.faces[f];
      areas[f] = 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).norm();
    }
  });
  return areas;
}

// The samples of triangle `face` in output slots [begin, end): Turk's sqrt(r1) barycentric
// coordinates, uniform over the triangle. Slot j's coordinates come from HashIndex(seed, j), so
// the result does not depend on the thread count.
void PlaceInTriangle(const SurfaceSampleOptions& o, const TriMesh& mesh, size_t face, uint64_t begin,
                     uint64_t end, PointCloud* out) {
  const auto& p = mesh.vertices.positions;
  const auto& t = mesh.faces[face];
  const Eigen::Vector3d a = p[t[0]], ab = p[t[1]] - a, ac = p[t[2]] - a;
  if (o.normals) {
    const Eigen::Vector3d n = ab.cross(ac);
    const double length = n.norm();
    const Eigen::Vector3f unit =
        length > 0 ? Eigen::Vector3f((n / length).cast<float>()) : Eigen::Vector3f::Zero();
    std::fill(out->normals.begin() + begin, out->normals.begin() + end, unit);
  }
  for (uint64_t j = begin; j < end; ++j) {
    // One 64-bit hash gives both coordinates (32 bits each: 2^-32 is far below any mesh detail).
    const uint64_t h = HashIndex(o.seed, j, 2);
    const double s = std::sqrt(static_cast<double>(h >> 32) * 0x1.0p-32);
    const double r = static_cast<double>(h & 0xffffffffu) * 0x1.0p-32;
    out->positions[j] = a + s * ((1 - r) * ab + r * ac);
  }
}

PointCloud EmptyCloud(const SurfaceSampleOptions& o, const TriMesh& mesh, size_t count) {
  PointCloud cloud;
  cloud.frame = mesh.vertices.frame;
  PointSchema schema;
  schema.normals = o.normals;
  schema.colors = o.colour.has_value();
  schema.layers = o.layer >= 0;
  cloud.SetSchema(schema);
  cloud.Resize(count);
  if (o.colour) std::fill(cloud.colors.begin(), cloud.colors.end(), *o.colour);
  if (o.layer >= 0) std::fill(cloud.layers.begin(), cloud.layers.end(), o.layer);
  return cloud;
}

}  // namespace

void SurfaceSampleOptions::Check() const {
  CANDI_CHECK_OPTION(density >= 0 && std::isfinite(density), density, "finite and >= 0");
  CANDI_CHECK_OPTION_MSG(mode != SurfaceSamplingMode::kArea || (count > 0) != (density > 0), count,
                         "exactly one of count and density must be > 0");
  CANDI_CHECK_OPTION(mode != SurfaceSamplingMode::kPerTriangle || per_triangle >= 1, per_triangle,
                     ">= 1");
  CANDI_CHECK_OPTION(threads >= 0, threads, ">= 0 (0 = all available)");
  CANDI_CHECK_OPTION_IN(layer, -1, 65535);
}

double MeshArea(const TriMesh& mesh) {
  const std::vector<double> areas = TriangleAreas(mesh, 0);
  return std::accumulate(areas.begin(), areas.end(), 0.0);
}

PointCloud SampleSurface(const SurfaceSampleOptions& options, const TriMesh& mesh) {
  options.Check();
  CANDI_CHECK(mesh.faces.size() < (uint64_t{1} << 32)) << "SampleSurface: over 2^32 faces";
  const std::vector<double> areas = TriangleAreas(mesh, options.threads);
  const double area = std::accumulate(areas.begin(), areas.end(), 0.0);
  if (options.mode == SurfaceSamplingMode::kPerTriangle) {
    const uint64_t n = static_cast<uint64_t>(options.per_triangle);
    PointCloud cloud = EmptyCloud(options, mesh, mesh.faces.size() * n);
    ParallelBlocks(options.threads, mesh.faces.size(), [&](size_t begin, size_t end) {
      for (size_t f = begin; f < end; ++f) PlaceInTriangle(options, mesh, f, f * n, (f + 1) * n, &cloud);
    });
    return cloud;
  }
  const uint64_t count = options.count > 0
                             ? options.count
                             : static_cast<uint64_t>(std::llround(options.density * area));
  if (count > 0 && !(area > 0)) {
    throw InputError("SampleSurface: the mesh has no area (" + std::to_string(mesh.faces.size()) +
                     " faces); cannot place " + std::to_string(count) + " points");
  }
  PointCloud cloud = EmptyCloud(options, mesh, count);
  if (count == 0) return cloud;
  // Exact count, i.i.d. area-uniform: draw each sample's triangle (alias table) and count the
  // draws per triangle (a multinomial), then place each triangle's samples in its own run of
  // output slots. Counting with atomic adds makes the counts, and so the output, independent of
  // the thread count; placing by triangle keeps the mesh reads sequential, and since a slot's
  // position depends only on (seed, slot), no sample-to-slot table is needed.
  const AliasTable table(areas);
  std::vector<uint64_t> start(mesh.faces.size() + 1, 0);
  auto count_faces = [&](auto zero) {  // 32-bit counters when they cannot overflow: half the cache
    std::vector<decltype(zero)> per_face(mesh.faces.size(), 0);
    ParallelBlocks(options.threads, count, [&](size_t begin, size_t end) {
      CountDraws(table, options.seed, begin, end, per_face.data());
    });
    for (size_t f = 0; f < mesh.faces.size(); ++f) start[f + 1] = start[f] + per_face[f];
  };
  if (count < (uint64_t{1} << 32)) {
    count_faces(uint32_t{0});
  } else {
    count_faces(uint64_t{0});
  }
  ParallelBlocks(options.threads, mesh.faces.size(), [&](size_t begin, size_t end) {
    for (size_t f = begin; f < end; ++f) PlaceInTriangle(options, mesh, f, start[f], start[f + 1], &cloud);
  });
  return cloud;
}

std::vector<uint64_t> SplitCount(uint64_t total, const std::vector<double>& weights) {
  const double sum = std::accumulate(weights.begin(), weights.end(), 0.0);
  CANDI_CHECK(!weights.empty() && sum > 0 && std::isfinite(sum))
      << "SplitCount: weights sum " << sum;
  std::vector<uint64_t> parts(weights.size());
  std::vector<std::pair<double, size_t>> remainders;
  uint64_t assigned = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    CANDI_CHECK(weights[i] >= 0) << "SplitCount: weight " << i << " = " << weights[i];
    const double exact = static_cast<double>(total) * (weights[i] / sum);
    parts[i] = std::min(total - assigned, static_cast<uint64_t>(std::floor(exact)));
    assigned += parts[i];
    remainders.emplace_back(exact - std::floor(exact), i);
  }
  std::stable_sort(remainders.begin(), remainders.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t k = 0; assigned < total; k = (k + 1) % remainders.size(), ++assigned) {
    ++parts[remainders[k].second];
  }
  return parts;
}

}  // namespace candi::sampling
