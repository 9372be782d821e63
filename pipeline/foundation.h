// The unreachable foundation from CAD sections (ALGORITHMS.md §2): each layer's section of the
// drawing becomes a surface (mesh/foundation.h), checked, and is sampled uniformly into points
// (sampling/surface_sampling.h) coloured by layer (the paper's Table 1). What `candi foundation`
// writes and what a build's foundation layer holds.
// Drawing units are metres after the DXF's $INSUNITS; points are in the drawing's frame (x
// horizontal, z up after the revolve). Failures: std::invalid_argument for invalid options,
// InputError naming the file and layer for a bad drawing. Thread-safe.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "mesh/foundation.h"
#include "sampling/surface_sampling.h"

namespace candi::pipeline {

// Points per m^2 when neither a count nor a density is given: the example at the paper's scale.
inline constexpr double kDefaultFoundationDensity = 50.0;

struct FoundationPointsOptions {
  mesh::FoundationOptions surface;       // drawing, section, profile (N), revolve (M), mesh, checks
  sampling::SurfaceSampleOptions sample;  // count, density or per_triangle (no default: set one), seed,
                                          // threads; the colour
                                          // and layer id of each layer are set here
  std::vector<std::string> layers;        // layers to build; empty: every layer holding a section
  void Check() const;
};

struct FoundationPoints {
  std::string unit_name;                      // the drawing's units ($INSUNITS)
  size_t drawing_layers = 0;                  // layers in the drawing
  std::vector<mesh::LayerSurface> surfaces;   // per built layer, in order
  std::vector<double> areas;                  // m^2
  std::vector<PointCloud> clouds;             // per layer: positions, normals, colour, layer id
  double mesh_seconds = 0, sample_seconds = 0;
  std::vector<std::string> Names() const;     // the built layers' names
  // Every layer's points in one cloud with a layer field and the "candi_layers" comment, as
  // io::WriteLayerClouds writes them (the first layer's frame).
  PointCloud Merged() const;
};

// The layers of `dxf` (an ASCII DXF file) as surfaces and points.
FoundationPoints DigitizeFoundation(const FoundationPointsOptions& options, const std::string& dxf);

}  // namespace candi::pipeline
