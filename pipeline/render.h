// Rendering point files, clouds in memory or one render archive see-through with SPBR, and
// writing the image: what `candi render` does, and `candi build` for each of its views.
//
// Point files and clouds are drawn in memory (a SplatCloud, 10 bytes a point copy; opacity
// control possible) or streamed in chunks (bounded memory); an archive is streamed from its
// memory-mapped chunks, a share of its ensembles at a time (the MPI split of `candi render`:
// pipeline/render_ranks.h runs the ranks and adds their sums). The camera is the view given, or the
// default view of the data (render/first_view.h) framed on the clipped bounds.
// World (survey) coordinates throughout; the renderers work in the data's render frame.
// Failures: std::invalid_argument for invalid options (the field named), InputError for bad or
// empty inputs. Not thread-safe (one render at a time per DensityCache).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/clip.h"
#include "core/field_colour.h"
#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/spbr_settings.h"
#include "io/image/png_io.h"
#include "render/archive.h"
#include "render/build_record.h"
#include "render/camera.h"
#include "render/first_view.h"
#include "render/spbr.h"
#include "sampling/density.h"
#include "sampling/opacity.h"

namespace candi::pipeline {

enum class RenderMode { kAuto, kMemory, kStream };

struct RenderOptions {
  // L, the seed (of the ensembles and of opacity control), point size and opaque (excludes
  // alpha); the image's size (a given view's own size unless size_given), background, brightness.
  ImageSettings image;
  bool size_given = false;       // the size replaces a given view's
  std::vector<double> alpha;     // opacity control per input (one value for all), each in [0, 1];
                                 // empty: every point once (or as its spbr_multiplicity says)
  int threads = 0;               // 0: all
  int preview = 0;               // > 0: only the first k ensembles
  RenderMode mode = RenderMode::kAuto;  // point files: auto streams above 1e6 points read in place, 5e7 others (alpha, preview: memory)
  uint64_t memory_budget = uint64_t{2048} << 20;  // bytes of z-buffers resident per pass (stream, archive)
  uint64_t chunk_budget = uint64_t{256} << 20;    // bytes of archive chunks mapped at once
  std::string columns;           // XYZ/PTS column spec of point files
  ClipRegion clip;               // world coordinates: only points inside are drawn
  // Archives: the share of a layer's points drawn, by the layer's name (as candi view's and a
  // site's "points ×f"; the others 1), each in [0, 16]; a name the archive lacks is an error.
  std::vector<std::pair<std::string, double>> layer_shares;
  std::optional<render::Camera> view;  // world coordinates; none: the default view of the data
  render::Orientation orientation;     // the default view's up and side
  // Points coloured by a scalar field (point files and clouds, drawn in memory: stream mode and
  // archives hold no fields); the 8-bit image then carries the legend.
  FieldColouring colour_by;
  void Check() const;
};

// Which of RenderOptions::image the caller set (the command line's flags); the others may come
// from a build's record (TakeBuildRenderSettings).
struct GivenImageSettings {
  bool repeat_level = false, seed = false, size = false, background = false, brightness = false;
};

// `options->image` with the render settings `record` says its build resolved (L, seed, image
// size, background, brightness) wherever `given` says the caller set none: `candi render BUILD`
// draws as the build's views did, as candi view and publish open it. False (nothing changed) for
// records of builds older than that block.
bool TakeBuildRenderSettings(const render::BuildRecord& record, const GivenImageSettings& given,
                             RenderOptions* options);

// What a render produced: the sums to average and the camera it was drawn from (world).
struct RenderedImage {
  render::SpbrResult result;
  render::Camera world_camera;
  std::string mode;              // "memory", "stream", "archive" (recorded in the PNG)
  std::optional<FieldLegend> legend;  // the colouring by a field, when options.colour_by asked
};

// The local density a point cloud's opacity control needs does not depend on the view: renders
// of the same data (a build renders each layer from several views) estimate it once. Keyed by
// the caller (a file's path, size and time; a build's layer).
class DensityCache {
 public:
  const sampling::DensityResult& Get(const std::string& key, const sampling::OpacityOptions& options,
                                     const PointCloud& cloud);

 private:
  std::map<std::string, sampling::DensityResult> densities_;
};

// The default view's orientation from a COLMAP model whose frame the points are in: up is the
// mean of its cameras' image-up directions (-y of each camera), and the view looks the mean way
// the cameras look, levelled. InputError for an unreadable model or one without registered images.
render::Orientation OrientationOfCameras(const std::string& colmap_model);

// Point files (PLY, LAS, LAZ, E57, XYZ, PTS) merged into one image, in memory or streamed
// (options.mode). Throws InputError naming a file that cannot be read, or when none holds a point.
RenderedImage RenderPointFiles(const RenderOptions& options, const std::vector<std::string>& files);

// Clouds in memory, as RenderPointFiles draws files in memory mode; names[k] names clouds[k] in
// messages, density_keys[k] its density in `cache`.
RenderedImage RenderClouds(const RenderOptions& options, const std::vector<const PointCloud*>& clouds,
                           const std::vector<std::string>& names, const std::vector<std::string>& density_keys,
                           DensityCache* cache);

// Ensembles [begin, end) of `archive` (this rank's share; the whole image for begin 0, end L):
// the sums of those ensembles and the camera. options.alpha must be empty (an archive holds each
// point once).
RenderedImage RenderArchiveEnsembles(const RenderOptions& options, const render::Archive& archive, int rank,
                                     int ranks);

// Where a render goes: an 8-bit PNG, optionally a 16-bit one and the view as JSON; inputs name
// the data in the PNG's text.
struct RenderOutputs {
  std::string png;
  std::string png16;
  std::string save_view;
  std::vector<std::string> inputs;
};

// The average image (brightness applied) written as PNG with its provenance text; returns the
// gain used. A field colouring's legend is drawn into the 8-bit PNG (the 16-bit one, for
// analysis, holds the render alone) and stated in the PNG's text.
double WriteRender(const RenderOptions& options, const RenderedImage& image, const RenderOutputs& outputs);

}  // namespace candi::pipeline
