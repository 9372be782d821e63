// The bundled Borobudur example's site: the inputs of every layer and the scene file that builds
// them (pipeline/build.h). `candi demo` makes it and builds it.
//
// The building is a procedural stand-in for the photogrammetric scan of the paper (which is not
// public): nine stacked platforms — six square, three circular carrying 72 perforated stupas —
// and the central stupa; a 113 m square base, ~35 m high; the balustrades of the galleries; and
// the foot encasement, the broad platform added in the 9th century that hides the original foot
// and its reliefs, with the southeast corner excavated as it is today. It is sampled as a UAV scan
// would be (uniform points on the visible surfaces; nothing inside the encasement). The foundation
// comes from examples/borobudur/foundation.dxf through the foundation path. The reliefs: 160
// Karmawibhangga panels on the original foot wall (156 hidden behind the encasement, 4 visible in
// the dig), each from a synthetic old photo (relief synth) through the shipped depth model,
// placed by Ceres from a documented-positions CSV (1 mm survey noise). The close range: the
// excavated corner photographed (photos candi renders of a solid model of the corner, with eight
// painted total-station targets), reconstructed by COLMAP structure from motion and candi's dense
// stereo, georeferenced on the targets picked in the photos, and merged over the coarse scan (it
// replaces the scan's points where it has its own). The site is written to OUT/inputs/ and the scene to
// OUT/scene.json (absolute paths), so every step can be repeated with `candi build`.
// Failures: std::invalid_argument for invalid options, InputError when OUT cannot be written.
// Not thread-safe.
#pragma once

#include <cstdint>
#include <string>

namespace candi::pipeline {

struct DemoSiteOptions {
  int width = 1024, height = 768;  // the views' pixels, [16, 16384]
  uint64_t seed = 1;               // every random step of the site (and of its build)
  bool quick = false;              // the reduced scene CI runs (fewer points, L = 32)
  bool full = false;               // paper scale: every panel through the network at the model's
                                   // resolution (default: hidden panels at the photo's); not with quick
  std::string source_dir;          // where examples/ is; "" = this build's source tree
  void Check() const;
};

// Writes the site into `output_dir` (created) and returns its scene file.
std::string MakeDemoSite(const DemoSiteOptions& options, const std::string& output_dir);

}  // namespace candi::pipeline
