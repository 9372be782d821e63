// Streaming SPBR of a render archive (perspective or orthographic views): memory-mapped chunks pass through the splat kernel, so the
// renderer holds frame buffers and a bounded batch of chunks, never the cloud.
//
// Ensemble e draws, of every visible chunk, the runs EnsembleSlices gives (render/archive.h): a
// preview of k ensembles reads k/L of the data. The image is the z-buffer of each ensemble's
// points, positions the float of the dequantized double, drawn by the same kernel as the other
// renderers with the same transform; it is the same, bit for bit, for any thread count, memory
// and chunk budget, any split of the ensembles (MPI, progressive batches): archive_test.cc
// checks it against a plain reference implementation.
// Chunks whose box lies wholly outside the view frustum (with a margin of the splat size) are
// skipped; this never changes the image, since the kernel would drop their points.
// A subset of the ensembles can be drawn (ensemble_begin/end): the integer sums of disjoint
// subsets add up to the whole render's (the MPI split, render/mpi/).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "core/clip.h"
#include "core/progress.h"
#include "core/spbr_settings.h"
#include "render/archive.h"
#include "render/camera.h"
#include "render/spbr.h"

namespace candi::render {

struct ArchiveRenderOptions {
  SpbrSettings spbr;  // L (1 when opaque), seed, point size
  // Bytes for resident z-buffers (12 bytes a pixel per ensemble, shared by the threads): the
  // ensembles beyond it take further passes over the chunks.
  uint64_t memory_budget = uint64_t{2} << 30;  // L = 100 at 1024² in one pass
  // Bytes of chunks mapped at once (kChunkBytesPerPoint a point). Must hold the largest visible
  // chunk.
  uint64_t chunk_budget = uint64_t{256} << 20;
  int threads = 0;                              // 0: as TBB allows
  int ensemble_begin = 0, ensemble_end = 0;     // ensembles drawn here; end 0 = L
  bool verify = true;                           // check each chunk's hash before drawing it
  // Per archive layer, the share of its points drawn (render/archive.h: opacity follows the
  // point-number law, alpha' = 1 - (1 - alpha)^f); 0 hides the layer (its chunks are not read).
  // Empty: 1 for every layer. Each in [0, 16].
  std::vector<double> layer_fraction;
  // Only points inside it are drawn (the archive's frame: ClipRegion::ToLocal of a world region);
  // chunks wholly outside are not read, chunks wholly inside are not tested point by point.
  ClipRegion clip;
  // In (0, 1]: of each run an ensemble draws, only its first share (rounded up): a random subset,
  // since a chunk's points are stored in random order. A preview of bounded cost (the viewer's,
  // when one whole ensemble would take long); below 1 the image is not part of any full render.
  double sample = 1.0;
  // Polled by the drawing threads every kCancelPoints points (so also within a chunk of huge
  // points); true aborts the render with RenderCancelled. Must be safe to call from any thread.
  // May be null.
  std::function<bool()> cancel;
  void Check() const;
};

// What RenderArchive throws when ArchiveRenderOptions::cancel says so.
struct RenderCancelled {};
inline constexpr uint64_t kCancelPoints = 4096;

inline constexpr uint64_t kChunkBytesPerPoint = 8;

struct ArchiveRenderStats {
  uint64_t chunks = 0, chunks_visible = 0;
  uint64_t chunks_clipped = 0;   // visible chunks the clip region cuts (tested point by point)
  uint64_t points_visible = 0;   // points in visible chunks (read once per pass)
  int passes = 0;
  int threads = 0;                // threads that drew
  int replicas = 1;               // copies of the z-buffers (fewer ensembles than threads), merged
  double seconds = 0;
};

// `camera` is perspective or orthographic, in the archive's frame (world - manifest().frame.origin). The result
// holds the sums of the drawn ensembles; `ensembles` and `repeat_level` are L.
// `progress` is called between groups of chunks; an exception it throws aborts the render (the
// viewer drops an image whose camera moved so).
SpbrResult RenderArchive(const ArchiveRenderOptions& options, const Camera& camera, const Archive& archive,
                         const ProgressCallback& progress = nullptr, ArchiveRenderStats* stats = nullptr);

// True when the chunk box (archive frame) may draw a pixel of `camera`, with `margin_px` pixels
// around the image.
bool BoxMayBeVisible(const Camera::Projector& projector, const Camera& camera, const Box3d& box, double margin_px);

// Ensembles [*begin, *end) of `rank` among `size` ranks: contiguous shares of L, sizes differing
// by at most one (a rank may get none when size > L). The MPI split (render/mpi/) and the viewer's
// batches use it.
void EnsembleShare(int repeat_level, int rank, int size, int* begin, int* end);

}  // namespace candi::render
