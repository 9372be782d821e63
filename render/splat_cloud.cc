#include "render/splat_cloud.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/check.h"

namespace candi::render {

void SplatCloudOptions::Check() const {
  if (repeat_level < 1) {
    throw std::invalid_argument("SplatCloudOptions::repeat_level = " + std::to_string(repeat_level) +
                                "; must be >= 1");
  }
  if (block_size != 0 && (block_size < 64 || block_size > 65536)) {
    throw std::invalid_argument("SplatCloudOptions::block_size = " + std::to_string(block_size) +
                                "; must be 0 (automatic) or in [64, 65536]");
  }
}

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

// 30-bit Morton code of a position on a 1024^3 grid over `box`.
uint32_t Morton30(const Eigen::Vector3d& p, const Box3d& box, const Eigen::Vector3d& inv_cell) {
  uint32_t code = 0;
  uint32_t cell[3];
  for (int k = 0; k < 3; ++k) {
    const double t = (p[k] - box.min[k]) * inv_cell[k];
    cell[k] = static_cast<uint32_t>(std::clamp(t, 0.0, 1023.0));
  }
  for (int bit = 9; bit >= 0; --bit) {
    for (int k = 0; k < 3; ++k) code = (code << 1) | ((cell[k] >> bit) & 1u);
  }
  return code;
}

// Stable LSD radix sort of indices by 30-bit codes (two 15-bit passes).
std::vector<uint32_t> SortByCode(const std::vector<uint32_t>& codes) {
  const size_t n = codes.size();
  std::vector<uint32_t> order(n), tmp(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  for (int shift : {0, 15}) {
    std::vector<size_t> count((1u << 15) + 1, 0);
    for (size_t i = 0; i < n; ++i) ++count[((codes[order[i]] >> shift) & 0x7fff) + 1];
    for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
    for (size_t i = 0; i < n; ++i) tmp[count[(codes[order[i]] >> shift) & 0x7fff]++] = order[i];
    order.swap(tmp);
  }
  return order;
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
  Box3d world;
  for (const PointCloud* c : clouds) world.Extend(c->WorldBounds());
  SplatCloud out;
  out.repeat_level = options.repeat_level;
  out.seed = options.seed;
  out.frame = RenderFrameFor(world);
  const Located located = Locate(clouds, out.frame);
  out.source_points = located.total;
  const size_t n = located.total;

  // Positions in the render frame, checked, and their Morton codes.
  std::vector<Eigen::Vector3f> local(n);
  std::vector<Rgb8> color(n);
  std::vector<uint16_t> multiplicity(n, 1);
  for (const Source& s : located.sources) {
    const PointCloud& c = *s.cloud;
    for (size_t i = 0; i < c.size(); ++i) {
      const Eigen::Vector3d p = c.positions[i] + s.shift;
      if (!p.allFinite()) {
        throw InputError("point " + std::to_string(s.first + i) + " of the render input has a NaN or "
                         "infinite coordinate");
      }
      local[s.first + i] = p.cast<float>();
      out.bounds.Extend(p);
      color[s.first + i] = c.schema.colors ? c.colors[i] : options.default_color;
      if (options.use_multiplicity && s.multiplicity != nullptr) {
        const double m = s.multiplicity->Get(i);
        // More copies than ensembles add nothing: each copy needs a distinct ensemble.
        const double cap = std::min(options.repeat_level, 65535);
        multiplicity[s.first + i] = static_cast<uint16_t>(std::isfinite(m) ? std::clamp(std::round(m), 0.0, cap) : 0.0);
      }
    }
  }
  if (progress) progress(n / 4, n);
  std::vector<uint32_t> codes(n);
  const Eigen::Vector3d inv_cell = (1024.0 / out.bounds.Extent().array().max(1e-9)).matrix();
  tbb::parallel_for(size_t{0}, n, [&](size_t i) { codes[i] = Morton30(local[i].cast<double>(), out.bounds, inv_cell); });
  const std::vector<uint32_t> order = SortByCode(codes);
  std::vector<uint32_t>().swap(codes);
  if (progress) progress(n / 2, n);

  // Copies per ensemble (counting sort); within an ensemble, Morton order.
  const int L = options.repeat_level;
  std::vector<uint64_t> start(L + 1, 0);
  for (uint32_t i : order) {
    const int e0 = EnsembleOf(options.seed, i, L);
    for (int j = 0; j < multiplicity[i]; ++j) ++start[(e0 + j) % L + 1];
  }
  for (int e = 0; e < L; ++e) start[e + 1] += start[e];
  const uint64_t copies = start[L];
  std::vector<uint32_t> source(copies);
  std::vector<uint64_t> fill(start.begin(), start.end() - 1);
  for (uint32_t i : order) {
    const int e0 = EnsembleOf(options.seed, i, L);
    for (int j = 0; j < multiplicity[i]; ++j) source[fill[(e0 + j) % L]++] = i;
  }

  // Blocks: cut each ensemble, quantize each block on its own bounding box.
  out.ensemble_blocks.assign(L + 1, 0);
  const uint64_t block_size =
      options.block_size > 0 ? options.block_size : std::clamp<uint64_t>(copies / L / 1024, 64, 4096);
  for (int e = 0; e < L; ++e) {
    for (uint64_t b = start[e]; b < start[e + 1]; b += block_size) {
      SplatBlock block{};
      block.begin = b;
      block.count = static_cast<uint32_t>(std::min<uint64_t>(block_size, start[e + 1] - b));
      out.blocks.push_back(block);
    }
    out.ensemble_blocks[e + 1] = out.blocks.size();
  }
  out.qx.resize(copies);
  out.qy.resize(copies);
  out.qz.resize(copies);
  out.colors.resize(copies);
  tbb::parallel_for(size_t{0}, out.blocks.size(), [&](size_t k) {
    SplatBlock& block = out.blocks[k];
    float lo[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                   std::numeric_limits<float>::max()};
    float hi[3] = {-lo[0], -lo[1], -lo[2]};
    for (uint64_t c = block.begin; c < block.begin + block.count; ++c) {
      const Eigen::Vector3f& p = local[source[c]];
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
      const Eigen::Vector3f& p = local[source[c]];
      const auto q = [&](int a) {
        return static_cast<uint16_t>(std::clamp(std::lround((p[a] - lo[a]) * inv[a]), 0L, 65535L));
      };
      out.qx[c] = q(0);
      out.qy[c] = q(1);
      out.qz[c] = q(2);
      out.colors[c] = PackColor(color[source[c]]);
    }
  });
  if (progress) progress(n, n);
  return out;
}

}  // namespace candi::render
