// The driver of the section lines: resolves the options and runs the stages, each in its own
// file, which says why (section_lines_internal.h lists them).
#include "section/section_lines.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"
#include "section/section_lines_internal.h"

namespace candi::section {

namespace {

using lines_internal::AdaptToNoise;
using lines_internal::BuildLines;
using lines_internal::BuildPointGrid;
using lines_internal::Context;
using lines_internal::CoverPoints;
using lines_internal::Edge;
using lines_internal::Forest;
using lines_internal::kMaxCells;
using lines_internal::kNone;
using lines_internal::LinkVertices;
using lines_internal::PruneSpurs;
using lines_internal::SpanningForest;
using lines_internal::TypicalPointGap;
using lines_internal::Vertex;

// Automatic values, as multiples of the typical point gap / of the spacing. 2.5 point gaps per
// vertex keep chords within s^2 / (8 R) = 1.6 mm of a curve of radius R = 20 m at 5 points/m;
// 6 spacings (15 point gaps) is a gap that Poisson sampling leaves by chance once in ~3e6.
constexpr double kSpacingPerPointGap = 2.5;
constexpr double kGapPerSpacing = 6.0;
constexpr double kMinLengthPerSpacing = 2.0;
// Fits: window radius, first and least biweight scale, as multiples of the spacing.
constexpr double kWindowPerSpacing = 3.0;
constexpr double kStartScalePerSpacing = 0.25;
constexpr double kScaleFloorPerSpacing = 0.02;

struct InputSummary {
  size_t finite = 0;
  bool distinct = false;  // at least two different finite points
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
};

InputSummary Summarize(const std::vector<Eigen::Vector2d>& points) {
  InputSummary s;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) continue;
    if (s.finite == 0) s.min = s.max = p;
    s.distinct = s.distinct || p != s.min || p != s.max;
    s.min = s.min.cwiseMin(p);
    s.max = s.max.cwiseMax(p);
    ++s.finite;
  }
  return s;
}

// The values used: given ones, else automatic from the typical point gap.
void ResolveScales(const SectionLineOptions& o, const std::vector<Eigen::Vector2d>& points,
                   const InputSummary& in, Context* ctx) {
  if (o.spacing > 0) {
    ctx->spacing = o.spacing;
  } else {
    const double gap = TypicalPointGap(points, in.min, in.finite);
    ctx->spacing = std::max(kSpacingPerPointGap * gap, o.min_spacing);
  }
  ctx->max_gap = o.max_gap > 0 ? o.max_gap : kGapPerSpacing * ctx->spacing;
  ctx->min_length = o.min_length > 0 ? o.min_length : kMinLengthPerSpacing * ctx->spacing;
  ctx->scales.radius = kWindowPerSpacing * ctx->spacing;
  ctx->scales.tau_start = kStartScalePerSpacing * ctx->spacing;
  ctx->scales.tau_floor = kScaleFloorPerSpacing * ctx->spacing;
  ctx->scales.gap = ctx->spacing;
  ctx->scales.adaptive = true;
  const double cells = std::floor((in.max - in.min).maxCoeff() / ctx->scales.radius) + 1;
  if (cells > static_cast<double>(kMaxCells)) {
    throw std::invalid_argument(
        "SectionLineOptions::spacing = " + FormatSignificant(ctx->spacing, 10) +
        (o.spacing > 0 ? "" : " (automatic)") + " makes " + FormatSignificant(cells, 10) +
        " cells along an axis; must be <= 2^31 (pass a larger spacing)");
  }
}

}  // namespace

void SectionLineOptions::Check() const {
  CANDI_CHECK_OPTION(spacing >= 0 && std::isfinite(spacing), spacing,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(max_gap >= 0 && std::isfinite(max_gap), max_gap,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(min_length >= 0 && std::isfinite(min_length), min_length,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(min_spacing > 0 && std::isfinite(min_spacing), min_spacing, "finite and > 0");
}

SectionLines ExtractSectionLines(const SectionLineOptions& options,
                                 const std::vector<Eigen::Vector2d>& points) {
  options.Check();
  SectionLines result;
  const InputSummary in = Summarize(points);
  result.points = in.finite;
  if (!in.distinct) return result;
  CANDI_CHECK(in.finite < kNone) << "ExtractSectionLines: " << in.finite
                                 << " points; at most 2^32-2";
  Context ctx;
  ResolveScales(options, points, in, &ctx);
  result.spacing = ctx.spacing;
  result.max_gap = ctx.max_gap;
  result.min_length = ctx.min_length;
  ctx.grid = BuildPointGrid(points, in.min, ctx.scales.radius);
  AdaptToNoise(&ctx);
  const std::vector<Vertex> vertices = CoverPoints(ctx);
  const std::vector<Edge> edges = LinkVertices(vertices, ctx);
  Forest forest = SpanningForest(vertices.size(), edges);
  PruneSpurs(vertices, ctx.min_length, &forest);
  result.lines = BuildLines(ctx, vertices, edges, forest, in.min);
  LogDebug("section lines: " + std::to_string(in.finite) + " points, " +
           std::to_string(vertices.size()) + " vertices, " + std::to_string(result.lines.size()) +
           " lines, spacing " + FormatSignificant(ctx.spacing, 10) + " m, max gap " +
           FormatSignificant(ctx.max_gap, 10) + " m, noise " + FormatSignificant(ctx.noise, 10) +
           " m");
  return result;
}

}  // namespace candi::section
