// A section through the archive: the points of a slab (an archive's chunks the slab crosses, or
// point files streamed), per layer, as an orthographic see-through SPBR image with a scale bar and
// as section lines (section/: lines, corners, DXF with one layer per archive layer, CSV, SVG),
// with a JSON summary. What `candi section` writes, and what the viewer's "export section" sends.
// Drawing coordinates and the slab are section/section_path.h's; world (survey) coordinates
// elsewhere. Failures: std::invalid_argument for invalid options (the field named) and for
// layers the inputs do not have, InputError for unreadable inputs or outputs.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/clip.h"
#include "core/image.h"
#include "core/spbr_settings.h"
#include "io/image/png_io.h"
#include "render/archive.h"
#include "section/section_outputs.h"
#include "section/section_path.h"
#include "view/protocol.h"

namespace candi::pipeline {

enum class SectionColours { kLayer, kData };  // one colour per layer, or the points' own

struct SectionOptions {
  double spacing = 0.0;         // section lines: vertex spacing, m, >= 0; 0 = from the points' density
  double max_gap = 0.0;         // section lines: a longer gap in the data breaks a line, m, >= 0; 0 = automatic
  int width = 1600;             // image pixels across, [16, 8192] (with pixel 0)
  double pixel = 0.0;           // image metres per pixel, >= 0; 0 = from width
  // The image's SPBR: L in [1, 10000] (a slab is thin: few ensembles blend it), its seed, the
  // point size (pixels); never opaque.
  SpbrSettings spbr = {10, 1, 2.0, false};
  double opacity = 0.7;         // image: of a pixel one slab point covers, (0, 1]
  SectionColours colours = SectionColours::kLayer;
  Rgb8 background{255, 255, 255};  // image background
  std::vector<std::string> layers;  // only these layers (empty: all)
  std::string columns;          // XYZ/PTS column spec of point files
  int threads = 0;              // 0: all
  // The most slab points (0: no limit): more is std::length_error, raised while reading, before
  // they are all held (the viewer's exports are bounded so).
  uint64_t max_points = 0;
  // Called between steps of the cut (chunk groups, layers, the image); an exception it throws
  // aborts the cut and passes through (the viewer cancels an export so). May be null.
  std::function<void()> checkpoint;
  void Check() const;
};

// A section cut, in memory: what it writes and what it prints.
struct SectionCut {
  std::vector<std::string> inputs;
  std::vector<section::SectionLayerResult> layers;  // per layer: points, lines (drawing coordinates)
  section::SectionWindow window;   // the image's place in drawing coordinates
  double scale_bar_m = 0;
  Image8 image;                    // section.png
  io::PngText image_text;
  std::string summary;             // section.json
  std::string describe;            // the section in words, every digit
  bool archive = false;            // read from an archive (chunk counts below)
  uint64_t chunks = 0, chunks_read = 0, points_read = 0;
  uint64_t Points() const;         // slab points of every layer
};

// Cuts `path` through `inputs` (an archive, a build directory or a demo's output holding one, or
// point files whose layer field names their layers) within `clip` (world coordinates).
SectionCut CutSection(const SectionOptions& options, const std::vector<std::string>& inputs,
                      const section::SectionPath& path, const ClipRegion& clip);

// Writes section.png, section.dxf, section.csv, section.svg and section.json into `dir`
// (created), each atomically.
void WriteSection(const SectionCut& cut, const section::SectionPath& path, const std::string& dir);

// The viewer's "export section": the slab of the page's request through the archive it shows,
// with the page's clipping and only its shown layers (view/protocol.h), as the reply message the
// page receives (JSON: type, seq, summary, dxf, svg, csv, png_base64). `base` gives the threads,
// max_points and checkpoint; its layers are replaced by the page's shown ones.
std::string ExportViewerSection(const std::string& archive_dir, const render::ArchiveManifest& manifest,
                                const SectionOptions& base, uint64_t seq, const view::SectionRequest& request,
                                const view::ViewState& state);

}  // namespace candi::pipeline
