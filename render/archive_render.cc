#include "render/archive_render.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/parallel.h"
#include "render/splat_cloud.h"
#include "render/splat_kernel.h"

namespace candi::render {

void ArchiveRenderOptions::Check() const {
  if (repeat_level < 1) {
    throw std::invalid_argument("ArchiveRenderOptions::repeat_level = " + std::to_string(repeat_level) +
                                "; must be >= 1");
  }
  if (!(point_size >= 1.0 && point_size <= 64.0)) {
    throw std::invalid_argument("ArchiveRenderOptions::point_size = " + std::to_string(point_size) +
                                "; must be in [1, 64] pixels");
  }
  if (threads < 0 || threads > 256) {
    throw std::invalid_argument("ArchiveRenderOptions::threads = " + std::to_string(threads) +
                                "; must be in [0, 256]");
  }
  const int end = ensemble_end == 0 ? repeat_level : ensemble_end;
  if (ensemble_begin < 0 || end > repeat_level || ensemble_begin > end) {
    throw std::invalid_argument("ArchiveRenderOptions: ensembles [" + std::to_string(ensemble_begin) + ", " +
                                std::to_string(end) + ") not within [0, " + std::to_string(repeat_level) + "]");
  }
}

bool BoxMayBeVisible(const Camera::Projector& p, const Camera& camera, const Box3d& box, double margin_px) {
  // Camera coordinates of the 8 corners; the box is out when all corners lie outside one plane
  // of the frustum (conservative: a box crossing a plane's extension stays in).
  Eigen::Vector3d c[8];
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d x(k & 1 ? box.max.x() : box.min.x(), k & 2 ? box.max.y() : box.min.y(),
                            k & 4 ? box.max.z() : box.min.z());
    c[k] = p.rotation * (x - p.eye);
  }
  const double near = p.near * (1 - 1e-6) - 1e-9;
  auto all = [&](auto outside) {
    for (const Eigen::Vector3d& v : c) {
      if (!outside(v)) return false;
    }
    return true;
  };
  if (all([&](const Eigen::Vector3d& v) { return v.z() < near; })) return false;
  const double left = -margin_px - p.cx, right = camera.width + margin_px - p.cx;
  const double top = -margin_px - p.cy, bottom = camera.height + margin_px - p.cy;
  // u - cx = f x / z: outside left when f x < left z (z > 0); corners behind the camera are
  // handled by keeping the box (they may wrap), unless all are behind (above).
  bool any_behind = false;
  for (const Eigen::Vector3d& v : c) any_behind |= v.z() <= 0;
  if (any_behind) return true;
  if (all([&](const Eigen::Vector3d& v) { return p.focal * v.x() < left * v.z(); })) return false;
  if (all([&](const Eigen::Vector3d& v) { return p.focal * v.x() > right * v.z(); })) return false;
  if (all([&](const Eigen::Vector3d& v) { return p.focal * v.y() < top * v.z(); })) return false;
  if (all([&](const Eigen::Vector3d& v) { return p.focal * v.y() > bottom * v.z(); })) return false;
  return true;
}

namespace {

// The points of one chunk staged for the resident ensembles, grouped by ensemble.
struct StagedChunk {
  std::vector<uint32_t> slot;       // per point: resident ensemble - first, or ~0
  std::vector<uint64_t> offsets;    // K + 1
  std::vector<float> x, y, z;
  std::vector<uint32_t> color;
  std::vector<uint64_t> index;      // archive index (point sizes > 1)
};

struct ThreadSums {
  Accumulator sums;
  std::array<uint64_t, 256> first_grey{};
  ThreadSums(int w, int h) : sums(w, h) {}
};

inline int Grey(uint64_t key) {
  const int r = (key >> 16) & 0xff, g = (key >> 8) & 0xff, b = key & 0xff;
  return (299 * r + 587 * g + 114 * b + 500) / 1000;
}

}  // namespace

SpbrResult RenderArchive(const ArchiveRenderOptions& options, const Camera& camera, const Archive& archive,
                         const ProgressCallback& progress, ArchiveRenderStats* stats_out) {
  options.Check();
  camera.Check();
  if (camera.projection != Projection::kPerspective) {
    throw std::invalid_argument("rendering an archive draws perspective views (depths must stay positive)");
  }
  const auto start = std::chrono::steady_clock::now();
  const int L = options.repeat_level;
  const int e_begin = options.ensemble_begin, e_end = options.ensemble_end == 0 ? L : options.ensemble_end;
  const ArchiveManifest& m = archive.manifest();
  const int w = camera.width, h = camera.height;
  const bool sized = options.point_size != 1.0;

  // Transform and projection exactly as SpbrStreamRenderer's (bit-identical images).
  const Camera::Projector projector = camera.MakeProjector();
  KernelTransform transform;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) transform.a[3 * r + k] = static_cast<float>(projector.rotation(r, k));
  }
  const Eigen::Vector3d b = -(projector.rotation * projector.eye);
  for (int r = 0; r < 3; ++r) transform.b[r] = static_cast<float>(b[r]);
  const KernelProjection projection{static_cast<float>(projector.focal), static_cast<float>(projector.cx),
                                    static_cast<float>(projector.cy), static_cast<float>(projector.near),
                                    true, w, h, 0, h};

  // Resident ensembles per pass.
  const double frame_bytes = 12.0 * w * h;
  if (options.memory_budget < frame_bytes) {
    throw std::invalid_argument("memory budget " + std::to_string(options.memory_budget >> 20) +
                                " MB is less than one " + std::to_string(w) + "x" + std::to_string(h) +
                                " z-buffer (" + std::to_string(static_cast<uint64_t>(frame_bytes) >> 20) + " MB)");
  }
  const int count = e_end - e_begin;
  const int per_pass = static_cast<int>(
      std::clamp(std::floor(options.memory_budget / frame_bytes), 1.0, static_cast<double>(std::max(count, 1))));
  const int passes = count == 0 ? 0 : (count + per_pass - 1) / per_pass;

  // Visible chunks, and the batches that fit the chunk budget.
  const uint64_t per_point = kChunkBytesPerPoint + (sized ? 8 : 0);
  const double margin = std::ceil(options.point_size) + 2.0;
  std::vector<size_t> visible;
  uint64_t visible_points = 0;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    if (!BoxMayBeVisible(projector, camera, m.chunks[k].quantizer.box, margin)) continue;
    if (m.chunks[k].count * per_point > options.chunk_budget) {
      throw std::invalid_argument("chunk budget " + std::to_string(options.chunk_budget) + " bytes is smaller than chunk " +
                                  std::to_string(k) + " of " + archive.directory() + " (" +
                                  std::to_string(m.chunks[k].count) + " points need " +
                                  std::to_string(m.chunks[k].count * per_point) + " bytes)");
    }
    visible.push_back(k);
    visible_points += m.chunks[k].count;
  }
  std::vector<std::pair<size_t, size_t>> batches;  // ranges of `visible`
  for (size_t i = 0; i < visible.size();) {
    size_t j = i;
    uint64_t bytes = 0;
    while (j < visible.size() && bytes + m.chunks[visible[j]].count * per_point <= options.chunk_budget) {
      bytes += m.chunks[visible[j]].count * per_point;
      ++j;
    }
    batches.push_back({i, j});
    i = j;
  }

  std::unique_ptr<tbb::task_arena> arena;
  if (options.threads > 0) arena = std::make_unique<tbb::task_arena>(options.threads);
  tbb::enumerable_thread_specific<ThreadSums> sums(w, h);
  std::vector<BandBuffer> buffers;
  std::vector<StagedChunk> staged;
  uint64_t copies = 0, done = 0;
  const uint64_t total_work = visible_points * static_cast<uint64_t>(passes);

  auto run = [&] {
    for (int pass = 0; pass < passes; ++pass) {
      const int first = e_begin + pass * per_pass, last = std::min(e_end, first + per_pass);
      const int K = last - first;
      buffers.resize(K);
      for (BandBuffer& buf : buffers) {
        if (buf.width != w || buf.rows != h) buf.Reset(w, h);
      }
      for (const auto& [bi, bj] : batches) {
        const size_t n = bj - bi;
        if (staged.size() < n) staged.resize(n);
        // Stage: decode each chunk's points of the resident ensembles, grouped by ensemble.
        ParallelFor(size_t{0}, n, [&](size_t j) {
          const size_t chunk = visible[bi + j];
          const ArchiveChunk& c = m.chunks[chunk];
          const uint64_t* words = archive.ChunkWords(chunk, options.verify);
          StagedChunk& s = staged[j];
          s.slot.resize(c.count);
          s.offsets.assign(K + 1, 0);
          for (uint64_t i = 0; i < c.count; ++i) {
            const int e = EnsembleOf(options.seed, c.first + i, L);
            const bool in = e >= first && e < last;
            s.slot[i] = in ? static_cast<uint32_t>(e - first) : ~uint32_t{0};
            if (in) ++s.offsets[e - first + 1];
          }
          for (int k = 0; k < K; ++k) s.offsets[k + 1] += s.offsets[k];
          const uint64_t staged_count = s.offsets[K];
          s.x.resize(staged_count), s.y.resize(staged_count), s.z.resize(staged_count);
          s.color.resize(staged_count);
          if (sized) s.index.resize(staged_count);
          std::vector<uint64_t> next(s.offsets.begin(), s.offsets.end() - 1);
          const ChunkQuantizer& q = c.quantizer;
          for (uint64_t i = 0; i < c.count; ++i) {
            if (s.slot[i] == ~uint32_t{0}) continue;
            const uint64_t at = next[s.slot[i]]++;
            const Eigen::Vector3d p = q.Decode(words[i]);
            s.x[at] = static_cast<float>(p.x());
            s.y[at] = static_cast<float>(p.y());
            s.z[at] = static_cast<float>(p.z());
            s.color[at] = ChunkQuantizer::Color(words[i]);
            if (sized) s.index[at] = c.first + i;
          }
          archive.Release(chunk);
        });
        // Splat: each resident ensemble draws its points of every staged chunk.
        ParallelFor(0, K, [&](int k) {
          for (size_t j = 0; j < n; ++j) {
            const StagedChunk& s = staged[j];
            const uint64_t a = s.offsets[k], e = s.offsets[k + 1];
            if (a == e) continue;
            if (!sized) {
              SplatPoints(transform, projection, &s.x[a], &s.y[a], &s.z[a], &s.color[a], e - a, &buffers[k]);
            } else {
              for (uint64_t i = a; i < e; ++i) {
                SplatPointsSized(transform, projection, &s.x[i], &s.y[i], &s.z[i], &s.color[i], 1,
                                 {options.point_size, options.seed, s.index[i]}, &buffers[k]);
              }
            }
          }
        });
        for (size_t j = 0; j < n; ++j) {
          copies += staged[j].offsets[K];
          done += m.chunks[visible[bi + j]].count;
        }
        if (progress) progress(done, total_work);
      }
      // Drain the pass's ensembles into the sums.
      ParallelFor(0, K, [&](int k) {
        ThreadSums& t = sums.local();
        if (first + k == 0) {
          buffers[k].Drain([&](uint32_t p, uint64_t key) {
            t.sums.Add(p, key);
            ++t.first_grey[Grey(key)];
          });
        } else {
          buffers[k].Drain([&](uint32_t p, uint64_t key) { t.sums.Add(p, key); });
        }
      });
    }
  };
  if (arena) arena->execute(run); else run();

  SpbrResult result;
  result.repeat_level = L;
  result.ensembles = L;
  result.seed = options.seed;
  result.copies = copies;
  result.sums = Accumulator(w, h);
  for (const ThreadSums& t : sums) {
    result.sums.Merge(t.sums);
    for (int i = 0; i < 256; ++i) result.first_ensemble_grey[i] += t.first_grey[i];
  }
  result.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (stats_out) {
    stats_out->chunks = m.chunks.size();
    stats_out->chunks_visible = visible.size();
    stats_out->points_visible = visible_points;
    stats_out->passes = passes;
    stats_out->seconds = result.milliseconds / 1000;
  }
  return result;
}

}  // namespace candi::render
