// What `candi view` shows: a render archive and what is known about it (its layers, the scene's
// saved views and render settings, a first view).
//
// - a build directory (`candi build`): its archive/, the layers and views of archive.json, each
//   view's camera (renders/<view>.view.json) and the scene's render settings;
// - a render archive (`candi pack`);
// - point files: packed on the fly into a temporary archive (removed when the viewer exits).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/field_colour.h"
#include "core/progress.h"
#include "render/archive.h"
#include "render/camera.h"
#include "render/first_view.h"
#include "view/protocol.h"

namespace candi::view {

struct SourceLayer {
  std::string name, kind;
  uint64_t points = 0;
  double opacity = 1;
  bool highlight = false;
};

struct SavedView {
  std::string name;
  render::Camera camera;  // world frame
  bool opaque = false;
};

struct ViewerSource {
  std::string title;
  std::string archive_dir;
  std::string kind;                 // "build", "archive" or "points"
  std::vector<SourceLayer> layers;  // empty when unknown
  std::vector<SavedView> views;
  ViewSettings settings;            // the scene's render settings, or the defaults
  render::Camera first_view;        // world frame
  std::string temporary_dir;        // points: the packed archive's directory (removed by the caller)
  int temporary_id = -1;            // its registration for removal on an interrupt (core/interrupt.h),
                                    // from before the pack: the caller unregisters it
  // A build's provenance for the page (JSON object, from archive.json): the CRS, the licence and
  // annotations the scene gives, and per layer its kind, whether it was measured (scanned) or
  // reconstructed, its method and its sources. Empty for an archive or point files.
  std::string provenance_json;
  // Points packed coloured by a scalar field (candi pack or view --colour-by; the archive's
  // manifest records it): the colouring, for the page's legend and the values of picks.
  std::optional<FieldLegend> legend;
  // A preview of point files (PackPreviewSource): one point in `preview_every` of the files'
  // `preview_points` was packed; 0: every point.
  uint64_t preview_every = 0, preview_points = 0;
  // The page's scene description (JSON): title, kind, layers, views, settings, first view,
  // bounds (world), origin, points, provenance (when known), the legend (when coloured).
  std::string ToJson(const render::ArchiveManifest& manifest) const;
};

// Opens a build directory or an archive (InputError naming the file for anything malformed).
ViewerSource OpenViewerSource(const std::string& path, const render::Orientation& orientation);
// A preview of point files for a first frame in seconds: when every file's points are records
// read in place (io/point_records.h: binary PLY, uncompressed LAS) and they hold more than twice
// `points` together, one record in k of each (k = the total / `points`, rounded up; the first of
// every k) packed into a fresh temporary directory, with the files' layers; else nullopt (the
// files are packed whole at once). The scene says it is a preview ("preview": {"every": k,
// "points": the files' total}).
std::optional<ViewerSource> PackPreviewSource(const std::vector<std::string>& files, const std::string& columns,
                                              const render::Orientation& orientation, uint64_t points,
                                              const ProgressCallback& progress);
// The k of PackPreviewSource's preview (one record in k), or 0 when it makes none.
uint64_t PreviewEvery(const std::vector<std::string>& files, const std::string& columns, uint64_t points);
// Packs point files into a fresh temporary directory; with `colour_by` active, the points
// coloured by that field (one legend over all the files; InputError naming a file without it).
ViewerSource PackViewerSource(const std::vector<std::string>& files, const std::string& columns,
                              const render::Orientation& orientation, const ProgressCallback& progress,
                              const FieldColouring& colour_by = FieldColouring());

}  // namespace candi::view
