#include "render/spbr_stream.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/check.h"
#include "core/parallel.h"
#include "io/point_records.h"
#include "render/splat_cloud.h"
#include "render/splat_kernel.h"

namespace candi::render {

void SpbrStreamOptions::Check() const {
  spbr.Check();
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

namespace {

// The points of one resident ensemble in the current chunk.
struct Staged {
  UninitVector<float> x, y, z;
  UninitVector<uint32_t> color;
  UninitVector<uint64_t> index;  // stream index of each point (for the point-size draws)
  void Clear() {
    x.clear(), y.clear(), z.clear(), color.clear(), index.clear();
  }
  void Resize(size_t n, bool indices) {
    x.resize(n), y.resize(n), z.resize(n), color.resize(n);
    if (indices) index.resize(n);
  }
};

// Points are staged in parallel blocks of this many (at least).
constexpr size_t kStageBlock = size_t{1} << 14;

struct ThreadSums {
  Accumulator sums;
  GreyHistogram first_grey{};
  ThreadSums(int w, int h) : sums(w, h) {}
};

}  // namespace

struct SpbrStreamRenderer::Impl {
  SpbrStreamOptions options;
  int L = 1;                  // the effective repeat level (1 when opaque)
  bool multiplicity = false;  // points draw their `spbr_multiplicity` copies
  Camera camera;
  Camera::Projector projector;
  LocalFrame frame;
  KernelTransform transform;
  KernelProjection projection;
  int per_pass = 1, pass = -1, first = 0, last = 0;
  bool gather = false;  // every point staged, each ensemble drawn at the end of the pass
  uint64_t next_index = 0, copies = 0;
  std::vector<BandBuffer> buffers;  // resident ensembles [first, last) (none when gathering)
  tbb::enumerable_thread_specific<BandBuffer> thread_buffers;  // gathering: one z-buffer a thread
  std::vector<Staged> staged;
  UninitVector<uint32_t> slots;   // Stage: each point's resident ensemble (K: none)
  std::vector<uint64_t> counts;   // Stage: per block and ensemble
  tbb::enumerable_thread_specific<ThreadSums> sums;
  std::unique_ptr<tbb::task_arena> arena;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  Impl(const SpbrStreamOptions& o, const Camera& c, const LocalFrame& f)
      : options(o),
        L(o.spbr.EffectiveRepeatLevel()),
        multiplicity(o.use_multiplicity && !o.spbr.opaque),
        camera(c),
        projector(c.MakeProjector()),
        frame(f),
        sums(c.width, c.height) {
    const double frame_bytes = 8.0 * c.width * c.height;
    if (o.memory_budget < frame_bytes) {
      throw std::invalid_argument("SpbrStreamOptions::memory_budget = " + std::to_string(o.memory_budget) +
                                  " bytes; less than one " + std::to_string(c.width) + "x" +
                                  std::to_string(c.height) + " z-buffer (" +
                                  std::to_string(static_cast<uint64_t>(frame_bytes)) + " bytes)");
    }
    per_pass = static_cast<int>(
        std::clamp(std::floor(o.memory_budget / frame_bytes), 1.0, static_cast<double>(L)));
    const double staged_bytes =
        (o.spbr.point_size != 1.0 ? 24.0 : 16.0) * static_cast<double>(o.expected_points);
    gather = o.expected_points > 0 && staged_bytes <= per_pass * frame_bytes;
    if (gather) per_pass = L;
    // c = R (p - eye) for positions p in the render frame (float, full precision).
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) transform.a[3 * r + k] = static_cast<float>(projector.rotation(r, k));
    }
    const Eigen::Vector3d b = -(projector.rotation * projector.eye);
    for (int r = 0; r < 3; ++r) transform.b[r] = static_cast<float>(b[r]);
    projection = {static_cast<float>(projector.focal), static_cast<float>(projector.cx),
                  static_cast<float>(projector.cy),
                  projector.perspective ? static_cast<float>(projector.near)
                                        : -std::numeric_limits<float>::infinity(),
                  projector.perspective, c.width, c.height, 0, c.height};
    if (o.threads > 0) arena = std::make_unique<tbb::task_arena>(o.threads);
  }

  template <typename F>
  void Run(F&& f) {
    if (arena) arena->execute(f); else f();
  }

  // Stages points [0, n) of the stream from next_index on, one copy each, for the resident
  // ensembles, by parallel blocks: decode(first, count, g) calls g(i, position, rgb) for points
  // [first, first + count) in order (the position in the render frame). Each ensemble's points
  // keep the stream's order, as a serial pass would stage them. Throws InputError for the first
  // NaN or infinite position.
  template <typename Decode>
  void Stage(size_t n, Decode&& decode);
  // Draws the staged points of resident ensemble k into `buffer`.
  void DrawEnsemble(int k, BandBuffer* buffer);
  // Draws the staged points into the resident z-buffers, ensembles in parallel.
  void Draw();
};

template <typename Decode>
void SpbrStreamRenderer::Impl::Stage(size_t n, Decode&& decode) {
  const size_t K = static_cast<size_t>(last - first);
  // Blocks of kStageBlock points, fewer and larger where many ensembles are resident (a small
  // image at a large L): the per-block counts stay within 2^22 entries.
  const size_t max_blocks = std::max<size_t>(1, (size_t{1} << 22) / (K + 1));
  const size_t block = std::max(kStageBlock, (n + max_blocks - 1) / max_blocks);
  const size_t blocks = (n + block - 1) / block;
  const bool indices = options.spbr.point_size != 1.0;
  if (n == 0) return;
  slots.resize(n);
  counts.assign(blocks * (K + 1), 0);  // per block, points per resident ensemble and the rest
  Run([&] {
    ParallelFor(size_t{0}, blocks, [&](size_t b) {
      uint64_t* count = counts.data() + b * (K + 1);
      for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
        const int e = EnsembleOf(options.spbr.seed, next_index + i, L);
        const uint32_t k = e >= first && e < last ? static_cast<uint32_t>(e - first) : static_cast<uint32_t>(K);
        slots[i] = k;
        ++count[k];
      }
    });
  });
  // Each block's first place in each ensemble, after the points staged before (gathering).
  for (size_t k = 0; k < K; ++k) {
    uint64_t at = staged[k].x.size();
    const uint64_t before = at;
    for (size_t b = 0; b < blocks; ++b) {
      const uint64_t c = counts[b * (K + 1) + k];
      counts[b * (K + 1) + k] = at;
      at += c;
    }
    staged[k].Resize(at, indices);
    copies += at - before;
  }
  std::vector<uint64_t> bad(blocks, std::numeric_limits<uint64_t>::max());
  Run([&] {
    ParallelFor(size_t{0}, blocks, [&](size_t b) {
      uint64_t* at = counts.data() + b * (K + 1);
      const size_t begin = b * block, m = std::min(n, begin + block) - begin;
      bool finite = true;
      decode(begin, m, [&](size_t i, const Eigen::Vector3d& p, uint32_t rgb) {
        if (!p.allFinite()) {
          if (finite) bad[b] = next_index + i;
          finite = false;
        }
        const uint32_t k = slots[i];
        if (k == K) return;
        Staged& s = staged[k];
        const uint64_t j = at[k]++;
        s.x[j] = static_cast<float>(p.x());
        s.y[j] = static_cast<float>(p.y());
        s.z[j] = static_cast<float>(p.z());
        s.color[j] = rgb;
        if (indices) s.index[j] = next_index + i;
      });
    });
  });
  const uint64_t first_bad = *std::min_element(bad.begin(), bad.end());
  if (first_bad != std::numeric_limits<uint64_t>::max()) {
    throw InputError("point " + std::to_string(first_bad) + " of the render input has a NaN or infinite coordinate");
  }
  next_index += n;
}

void SpbrStreamRenderer::Impl::DrawEnsemble(int k, BandBuffer* buffer) {
  Staged& s = staged[k];
  if (s.x.empty()) return;
  if (options.spbr.point_size == 1.0) {
    SplatPoints(transform, projection, s.x.data(), s.y.data(), s.z.data(), s.color.data(), s.x.size(), buffer);
  } else {
    // Draw point by point so each keeps its own stream index for the size draw.
    for (size_t i = 0; i < s.x.size(); ++i) {
      SplatPointsSized(transform, projection, &s.x[i], &s.y[i], &s.z[i], &s.color[i], 1,
                       {options.spbr.point_size, options.spbr.seed, s.index[i]}, buffer);
    }
  }
}

void SpbrStreamRenderer::Impl::Draw() {
  Run([&] { ParallelFor(0, last - first, [&](int k) { DrawEnsemble(k, &buffers[k]); }); });
}

SpbrStreamRenderer::SpbrStreamRenderer(const SpbrStreamOptions& options, const Camera& camera,
                                       const LocalFrame& frame) {
  options.Check();
  camera.Check();
  CANDI_CHECK(camera.projection == Projection::kPerspective)
      << "streaming SPBR draws perspective views (depths must stay positive); use a SplatCloud for "
         "orthographic views";
  impl_ = std::make_unique<Impl>(options, camera, frame);
}

SpbrStreamRenderer::~SpbrStreamRenderer() = default;

int SpbrStreamRenderer::passes() const {
  return (impl_->L + impl_->per_pass - 1) / impl_->per_pass;
}
int SpbrStreamRenderer::ensembles_per_pass() const { return impl_->per_pass; }

void SpbrStreamRenderer::BeginPass(int pass) {
  Impl& m = *impl_;
  CANDI_CHECK(pass >= 0 && pass < passes()) << "pass " << pass;
  m.pass = pass;
  m.first = pass * m.per_pass;
  m.last = std::min(m.L, m.first + m.per_pass);
  m.next_index = 0;
  m.staged.resize(m.last - m.first);
  if (m.gather) {
    // Room for each ensemble's expected share (a little more: the shares vary).
    const uint64_t share = m.options.expected_points / static_cast<uint64_t>(m.L);
    const bool indices = m.options.spbr.point_size != 1.0;
    for (Staged& s : m.staged) {
      s.Clear();
      const size_t room = static_cast<size_t>(share + share / 16 + 64);
      s.x.reserve(room), s.y.reserve(room), s.z.reserve(room), s.color.reserve(room);
      if (indices) s.index.reserve(room);
    }
    return;
  }
  m.buffers.resize(m.last - m.first);
  m.Run([&] {
    ParallelFor(size_t{0}, m.buffers.size(), [&](size_t k) {  // fresh pages: faulting them in is most of it
      BandBuffer& b = m.buffers[k];
      if (b.width != m.camera.width || b.rows != m.camera.height) b.Reset(m.camera.width, m.camera.height);
    });
  });
}

void SpbrStreamRenderer::Add(const PointCloud& chunk) {
  Impl& m = *impl_;
  CANDI_CHECK(m.pass >= 0) << "Add before BeginPass";
  const Eigen::Vector3d shift = chunk.frame.origin - m.frame.origin;
  const ScalarField* mult = m.multiplicity ? chunk.FindScalar(kMultiplicityField) : nullptr;
  const uint32_t fallback = PackColor(m.options.default_color);
  if (!m.gather) for (Staged& s : m.staged) s.Clear();
  if (!mult) {
    m.Stage(chunk.size(), [&](size_t first, size_t count, auto&& g) {
      for (size_t i = first; i < first + count; ++i) {
        g(i, chunk.positions[i] + shift, chunk.schema.colors ? PackColor(chunk.colors[i]) : fallback);
      }
    });
    if (!m.gather) m.Draw();
    return;
  }
  // Points with multiplicities: m copies in m ensembles, staged serially.
  const int L = m.L;
  for (size_t i = 0; i < chunk.size(); ++i) {
    const uint64_t index = m.next_index + i;
    const Eigen::Vector3d p = chunk.positions[i] + shift;
    if (!p.allFinite()) {
      throw InputError("point " + std::to_string(index) + " of the render input has a NaN or infinite coordinate");
    }
    const int copies = static_cast<int>(std::clamp(std::round(mult->Get(i)), 0.0, double(L)));
    ForEachEnsemble(m.options.spbr.seed, index, copies, L, [&](int e) {
      if (e < m.first || e >= m.last) return;
      Staged& s = m.staged[e - m.first];
      s.x.push_back(static_cast<float>(p.x()));
      s.y.push_back(static_cast<float>(p.y()));
      s.z.push_back(static_cast<float>(p.z()));
      s.color.push_back(PackColor(chunk.schema.colors ? chunk.colors[i] : m.options.default_color));
      s.index.push_back(index);
      ++m.copies;
    });
  }
  m.next_index += chunk.size();
  if (!m.gather) m.Draw();
}

void SpbrStreamRenderer::AddRecords(const uint8_t* records, const io::PointRecordLayout& layout,
                                    const Eigen::Vector3d& origin, size_t n) {
  Impl& m = *impl_;
  CANDI_CHECK(m.pass >= 0) << "AddRecords before BeginPass";
  const Eigen::Vector3d shift = origin - m.frame.origin;
  const uint32_t fallback = PackColor(m.options.default_color);
  if (!m.gather) for (Staged& s : m.staged) s.Clear();
  m.Stage(n, [&](size_t first, size_t count, auto&& g) {
    io::ForEachRecord(layout, records + first * layout.stride, count, fallback,
                      [&](size_t i, const Eigen::Vector3d& p, uint32_t rgb) { g(first + i, p + shift, rgb); });
  });
  if (!m.gather) m.Draw();
}

void SpbrStreamRenderer::EndPass() {
  Impl& m = *impl_;
  CANDI_CHECK(m.pass >= 0) << "EndPass before BeginPass";
  m.Run([&] {
    ParallelFor(0, m.last - m.first, [&](int k) {
      ThreadSums& t = m.sums.local();
      BandBuffer* buffer = nullptr;
      if (m.gather) {  // the ensemble's points, all gathered: drawn in this thread's z-buffer
        buffer = &m.thread_buffers.local();
        if (buffer->width != m.camera.width || buffer->rows != m.camera.height) {
          buffer->Reset(m.camera.width, m.camera.height);
        }
        m.DrawEnsemble(k, buffer);
        Staged drawn;
        std::swap(drawn, m.staged[k]);  // its memory goes back now
      } else {
        buffer = &m.buffers[k];
      }
      buffer->DrainInto(&t.sums, m.first + k == 0 ? &t.first_grey : nullptr);
    });
  });
  m.pass = -1;
}

SpbrResult SpbrStreamRenderer::Finish() {
  Impl& m = *impl_;
  SpbrResult result;
  result.repeat_level = m.L;
  result.ensembles = m.L;
  result.seed = m.options.spbr.seed;
  result.copies = m.copies;
  result.sums = Accumulator(m.camera.width, m.camera.height);
  for (const ThreadSums& t : m.sums) {
    result.sums.Merge(t.sums);
    for (int i = 0; i < 256; ++i) result.first_ensemble_grey[i] += t.first_grey[i];
  }
  result.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - m.start).count();
  return result;
}

}  // namespace candi::render
