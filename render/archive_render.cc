#include "render/archive_render.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/parallel.h"
#include "render/splat_cloud.h"
#include "render/splat_kernel.h"

namespace candi::render {

void ArchiveRenderOptions::Check() const {
  spbr.Check();
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
  CANDI_CHECK_OPTION_EACH_IN(layer_fraction, 0, 16);
  clip.Check("ArchiveRenderOptions::clip");
  CANDI_CHECK_OPTION(sample > 0 && sample <= 1, sample, "in (0, 1]");
  const int L = spbr.EffectiveRepeatLevel();
  const int end = ensemble_end == 0 ? L : ensemble_end;
  CANDI_CHECK_OPTION_PAIR(ensemble_begin >= 0 && end <= L && ensemble_begin <= end, ensemble_begin,
                          ensemble_end,
                          "ensembles [" + std::to_string(ensemble_begin) + ", " +
                              std::to_string(end) + ") not within [0, " + std::to_string(L) + "]");
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
  auto all = [&](auto outside) {
    for (const Eigen::Vector3d& v : c) {
      if (!outside(v)) return false;
    }
    return true;
  };
  const double left = -margin_px - p.cx, right = camera.width + margin_px - p.cx;
  const double top = -margin_px - p.cy, bottom = camera.height + margin_px - p.cy;
  if (!p.perspective) {
    // u - cx = f x: the slab of the image's rows and columns, whatever the depth.
    if (all([&](const Eigen::Vector3d& v) { return p.focal * v.x() < left; })) return false;
    if (all([&](const Eigen::Vector3d& v) { return p.focal * v.x() > right; })) return false;
    if (all([&](const Eigen::Vector3d& v) { return p.focal * v.y() < top; })) return false;
    if (all([&](const Eigen::Vector3d& v) { return p.focal * v.y() > bottom; })) return false;
    return true;
  }
  const double near = p.near * (1 - 1e-6) - 1e-9;
  if (all([&](const Eigen::Vector3d& v) { return v.z() < near; })) return false;
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

struct ThreadSums {
  Accumulator sums;
  GreyHistogram first_grey{};
  ThreadSums(int w, int h) : sums(w, h) {}
};

// Transform and projection exactly as SpbrStreamRenderer's (bit-identical images). Orthographic
// views shift every depth by `depth_offset` (OrthographicDepthOffset) so that all drawn ones are
// positive, as the kernel's keys need.
struct Kernel {
  KernelTransform transform;
  KernelProjection projection;
};
Kernel MakeKernel(const Camera::Projector& projector, int w, int h, double depth_offset) {
  Kernel k;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) k.transform.a[3 * r + c] = static_cast<float>(projector.rotation(r, c));
  }
  Eigen::Vector3d b = -(projector.rotation * projector.eye);
  b.z() += depth_offset;
  for (int r = 0; r < 3; ++r) k.transform.b[r] = static_cast<float>(b[r]);
  const float near = projector.perspective ? static_cast<float>(projector.near) : -std::numeric_limits<float>::infinity();
  k.projection = {static_cast<float>(projector.focal), static_cast<float>(projector.cx),
                  static_cast<float>(projector.cy), near, projector.perspective, w, h, 0, h};
  return k;
}

// The chunks whose boxes may draw a pixel; each must fit the chunk budget. `cut`: per archive
// chunk, whether the clip region cuts it (its points are tested one by one).
std::vector<size_t> VisibleChunks(const ArchiveRenderOptions& options, const Camera& camera,
                                  const Camera::Projector& projector, const Archive& archive, uint64_t* points,
                                  std::vector<uint8_t>* cut) {
  const ArchiveManifest& m = archive.manifest();
  const double margin = std::ceil(options.spbr.point_size) + 2.0;
  std::vector<size_t> visible;
  *points = 0;
  if (!options.layer_fraction.empty() && options.layer_fraction.size() != m.layers.size()) {
    throw std::invalid_argument("layer_fraction: " + std::to_string(options.layer_fraction.size()) + " values for " +
                                std::to_string(m.layers.size()) + " layers of " + archive.directory());
  }
  cut->assign(m.chunks.size(), 0);
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    if (!options.layer_fraction.empty() && options.layer_fraction[m.chunks[k].layer] == 0) continue;  // hidden
    const ClipRelation relation = options.clip.Classify(m.chunks[k].quantizer.box);
    if (relation == ClipRelation::kOutside) continue;
    (*cut)[k] = relation == ClipRelation::kPartial ? 1 : 0;
    if (!BoxMayBeVisible(projector, camera, m.chunks[k].quantizer.box, margin)) continue;
    const uint64_t bytes = m.chunks[k].count * kChunkBytesPerPoint;
    if (bytes > options.chunk_budget) {
      throw std::invalid_argument("chunk budget " + std::to_string(options.chunk_budget) + " bytes is smaller than chunk " +
                                  std::to_string(k) + " of " + archive.directory() + " (" +
                                  std::to_string(m.chunks[k].count) + " points need " + std::to_string(bytes) +
                                  " bytes)");
    }
    visible.push_back(k);
    *points += m.chunks[k].count;
  }
  return visible;
}

// Groups of the visible chunks (ranges of `visible`) within the chunk budget and of at most
// `most` chunks: a group's chunks are drawn, then released together (one TLB flush per run of
// adjacent chunks), and progress is reported between groups.
std::vector<std::pair<size_t, size_t>> ChunkGroups(const std::vector<size_t>& visible, const ArchiveManifest& m,
                                                   uint64_t budget, size_t most) {
  std::vector<std::pair<size_t, size_t>> groups;
  for (size_t i = 0; i < visible.size();) {
    size_t j = i;
    uint64_t bytes = 0;
    while (j < visible.size() && j - i < most && bytes + m.chunks[visible[j]].count * kChunkBytesPerPoint <= budget) {
      bytes += m.chunks[visible[j]].count * kChunkBytesPerPoint;
      ++j;
    }
    groups.push_back({i, j});
    i = j;
  }
  return groups;
}

QuantizedPoints PointsOf(const ArchiveChunk& c, const uint64_t* words, const PointRun& run, const ClipRegion* clip) {
  QuantizedPoints points;
  points.clip = clip;
  points.words = words + run.begin;
  points.count = run.end - run.begin;
  points.first_index = c.first + run.begin;
  for (int a = 0; a < 3; ++a) {
    points.min[a] = c.quantizer.box.min[a];
    points.step[a] = c.quantizer.step[a];
    points.bits[a] = c.quantizer.bits[a];
  }
  return points;
}

// What one thread draws: ensembles [first, first + count) of the render into its buffers'
// ensembles [base, base + count).
struct Share {
  int first = 0, count = 0, base = 0;
};

// One thread's share of a group. The threads form `replicas` groups, each drawing every
// replicas-th chunk into its own copy of the z-buffers; within a replica, `sharers` threads
// split the ensembles (`share`: this thread's). Thread t = sharer * replicas + replica; it
// checks the hashes of the chunks it is the first to read in its replica's turn (a corrupt chunk
// fails the render whichever thread reads it first). Returns the points drawn.
uint64_t DrawShare(const ArchiveRenderOptions& o, const Archive& archive, const std::vector<size_t>& visible, size_t g,
                   size_t g_end, int replica, int replicas, int sharer, int sharers, const Kernel& kernel,
                   const Share& share, const std::vector<uint8_t>& cut, EnsembleBuffers* buffers) {
  uint64_t drawn = 0;
  std::vector<PointRun> runs;
  const ArchiveManifest& m = archive.manifest();
  for (size_t j = g; j < g_end; ++j) {
    if (j % replicas != static_cast<size_t>(replica)) continue;
    const bool check = o.verify && (j / replicas) % sharers == static_cast<size_t>(sharer);
    const uint64_t* words = archive.ChunkWords(visible[j], check);
    const ArchiveChunk& c = m.chunks[visible[j]];
    const double fraction = o.layer_fraction.empty() ? 1.0 : o.layer_fraction[c.layer];
    const ClipRegion* clip = cut[visible[j]] ? &o.clip : nullptr;
    for (int e = 0; e < share.count; ++e) {
      runs.clear();
      EnsembleSlices(c.count, c.first, o.spbr.EffectiveRepeatLevel(), o.spbr.seed, share.first + e,
                     fraction, &runs);
      EnsembleSelection selection;
      selection.seed = o.spbr.seed;
      selection.base = share.base + e;
      selection.point_size = o.spbr.point_size;
      for (PointRun run : runs) {
        if (o.sample < 1) {
          const double n = std::ceil(o.sample * static_cast<double>(run.end - run.begin));
          run.end = run.begin + std::min(run.end - run.begin, static_cast<uint64_t>(n));
        }
        if (!o.cancel) {
          drawn += SplatQuantized(kernel.transform, kernel.projection, PointsOf(c, words, run, clip), selection, buffers);
          continue;
        }
        // Pieces of the run, in order (the same image), with a poll between them.
        for (uint64_t b = run.begin; b < run.end; b += kCancelPoints) {
          if (o.cancel()) throw RenderCancelled{};
          const PointRun piece{b, std::min(run.end, b + kCancelPoints)};
          drawn += SplatQuantized(kernel.transform, kernel.projection, PointsOf(c, words, piece, clip), selection, buffers);
        }
      }
    }
  }
  return drawn;
}

}  // namespace

SpbrResult RenderArchive(const ArchiveRenderOptions& options, const Camera& camera, const Archive& archive,
                         const ProgressCallback& progress, ArchiveRenderStats* stats_out) {
  options.Check();
  camera.Check();
  const auto start = std::chrono::steady_clock::now();
  const int L = options.spbr.EffectiveRepeatLevel();
  const int e_begin = options.ensemble_begin, e_end = options.ensemble_end == 0 ? L : options.ensemble_end;
  const ArchiveManifest& m = archive.manifest();
  const int w = camera.width, h = camera.height;
  const Camera::Projector projector = camera.MakeProjector();
  const Kernel kernel = MakeKernel(projector, w, h, OrthographicDepthOffset(projector, m.bounds));
  uint64_t visible_points = 0;
  std::vector<uint8_t> cut;
  const std::vector<size_t> visible = VisibleChunks(options, camera, projector, archive, &visible_points, &cut);

  // Resident ensembles (12 bytes a pixel each) and passes. The threads share the ensembles of a
  // pass, each drawing its own range of them from every visible point, so no z-buffer is held
  // twice and none is merged. With fewer ensembles than threads (opaque renders, small L, a
  // rank's small share) that would idle threads: then, budget permitting, every thread draws its
  // share of the chunks into its own copy of all the z-buffers, min-merged at the end (the image
  // does not change: the nearest key per pixel is the nearest of the copies').
  const double frame_bytes = 12.0 * w * h;
  if (options.memory_budget < frame_bytes) {
    throw std::invalid_argument("memory budget " + std::to_string(options.memory_budget >> 20) +
                                " MB is less than one " + std::to_string(w) + "x" + std::to_string(h) +
                                " z-buffer (" + std::to_string(static_cast<uint64_t>(frame_bytes) >> 20) + " MB)");
  }
  const int count = e_end - e_begin;
  const int per_pass = static_cast<int>(
      std::clamp(std::floor(options.memory_budget / frame_bytes), 1.0, static_cast<double>(std::max(count, 1))));
  const int passes = count == 0 || visible.empty() ? 0 : (count + per_pass - 1) / per_pass;
  const int wanted = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  int replicas = 1, sharers = std::clamp(wanted, 1, per_pass);
  if (passes == 1 && wanted > per_pass) {
    const double copies_fit = std::floor(options.memory_budget / (frame_bytes * per_pass));
    replicas = static_cast<int>(std::clamp(copies_fit, 1.0, static_cast<double>(std::min<size_t>(wanted, visible.size()))));
    if (replicas > 1) sharers = 1;
  }
  const int threads = replicas * sharers;
  const auto groups = ChunkGroups(visible, m, options.chunk_budget, static_cast<size_t>(64 * threads));

  tbb::task_arena arena(threads);
  std::vector<std::unique_ptr<EnsembleBuffers>> buffers(passes > 0 ? replicas : 0);
  for (auto& b : buffers) b = std::make_unique<EnsembleBuffers>(w, h, per_pass);
  tbb::enumerable_thread_specific<ThreadSums> sums(w, h);
  std::vector<uint64_t> copies(threads, 0);
  uint64_t done = 0;
  const uint64_t total_work = visible_points * static_cast<uint64_t>(passes);

  arena.execute([&] {
    for (int pass = 0; pass < passes; ++pass) {
      const int first = e_begin + pass * per_pass, K = std::min(e_end, first + per_pass) - first;
      for (const auto& [g, g_end] : groups) {
        const auto release = [&, g = g, g_end = g_end] {
          archive.Release(std::vector<size_t>(visible.begin() + g, visible.begin() + g_end));
        };
        try {
          ParallelFor(0, threads, [&, g = g, g_end = g_end](int t) {
            // Sharer s of a replica draws the pass's ensembles [K s / S, K (s + 1) / S).
            const int replica = t % replicas, sharer = t / replicas;
            const int k0 = static_cast<int>(int64_t{K} * sharer / sharers);
            const int k1 = static_cast<int>(int64_t{K} * (sharer + 1) / sharers);
            EnsembleBuffers* mine = buffers[replica].get();
            if (k1 > k0) mine->Prepare(k0, k1);
            const Share share{first + k0, k1 - k0, k0};
            copies[t] += DrawShare(options, archive, visible, g, g_end, replica, replicas, sharer, sharers, kernel, share,
                                   cut, mine);
          });
        } catch (...) {  // cancelled, a corrupt chunk: the group's chunks are released all the same
          release();
          throw;
        }
        release();
        for (size_t j = g; j < g_end; ++j) done += m.chunks[visible[j]].count;
        if (progress) progress(done, total_work);
      }
      // The pass's ensembles (the copies merged first) into the sums.
      ParallelFor(0, K, [&](int k) {
        for (int r = 1; r < replicas; ++r) buffers[0]->Absorb(k, buffers[r].get());
        ThreadSums& t = sums.local();
        buffers[0]->DrainInto(k, &t.sums, first + k == 0 ? &t.first_grey : nullptr);
      });
    }
  });

  SpbrResult result;
  result.repeat_level = L;
  result.ensembles = L;
  result.seed = options.spbr.seed;
  for (uint64_t c : copies) result.copies += c;
  result.sums = Accumulator(w, h);
  for (const ThreadSums& t : sums) {
    result.sums.Merge(t.sums);
    for (int i = 0; i < 256; ++i) result.first_ensemble_grey[i] += t.first_grey[i];
  }
  result.milliseconds = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (stats_out) {
    stats_out->chunks = m.chunks.size();
    stats_out->chunks_visible = visible.size();
    stats_out->chunks_clipped = 0;
    for (size_t k : visible) stats_out->chunks_clipped += cut[k];
    stats_out->points_visible = visible_points;
    stats_out->passes = passes;
    stats_out->threads = threads;
    stats_out->replicas = replicas;
    stats_out->seconds = result.milliseconds / 1000;
  }
  return result;
}

void EnsembleShare(int repeat_level, int rank, int size, int* begin, int* end) {
  CANDI_CHECK(size >= 1 && rank >= 0 && rank < size) << "rank " << rank << " of " << size;
  const int64_t L = repeat_level;
  *begin = static_cast<int>(L * rank / size);
  *end = static_cast<int>(L * (rank + 1) / size);
}

}  // namespace candi::render
