// What a section shows besides the DXF (section_dxf.h): the section image's scale bar, the SVG
// drawing and the CSV of the lines' vertices, as text (pipeline/section.h writes them).
// Thread-safe (pure functions).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/point_cloud.h"
#include "core/polyline.h"
#include "section/section_path.h"

namespace candi::section {

struct SectionLayerResult {
  std::string name;
  Rgb8 colour;
  uint64_t points = 0;            // slab points of the layer
  bool area = false;              // its points fill an area (a layer lying in the plane): no lines
  std::vector<Polyline2> lines;   // drawing coordinates, m
  double length = 0;              // of the lines, m
};

// The drawing's window: drawing coordinates of the image's corners.
struct SectionWindow {
  double x0 = 0, y0 = 0;          // bottom-left, m
  double metres_per_pixel = 1;
  int width = 0, height = 0;
};

// A bar of a round length (1, 2 or 5 x 10^k m) about a fifth of the image wide, with end ticks
// and its length written beside it, at the bottom-left corner; black on light backgrounds, white
// on dark ones. Returns the bar's length in metres.
double DrawScaleBar(const SectionWindow& window, Rgb8 background, Image8* image);

// CSV, per layer: layer, line, vertex, closed, x, y (drawing, m) and X, Y, Z (world).
std::string SectionCsv(const std::vector<SectionLayerResult>& layers, const SectionPath& section);
// An SVG in drawing coordinates (1 unit = 1 m, y up): the image underneath (`image_href`, relative),
// one group per layer, a scale bar and a legend.
std::string SectionSvg(const std::vector<SectionLayerResult>& layers, const SectionWindow& window,
                       const std::string& image_href, const std::string& title, double bar_metres);

}  // namespace candi::section
