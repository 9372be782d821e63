// Stage 2 of the section lines (section_lines_internal.h): the cover, vertices on the curves.
#include "section/section_lines_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace candi::section::lines_internal {

std::vector<Vertex> CoverPoints(const Context& ctx) {
  const std::vector<Eigen::Vector2d>& points = ctx.grid.points;
  const double reach = 0.5 * ctx.spacing;  // covered along the curve each way
  std::vector<uint8_t> covered(points.size(), 0);
  std::vector<Vertex> vertices;
  Window win;
  for (size_t k = 0; k < points.size(); ++k) {
    if (covered[k]) continue;
    covered[k] = 1;
    Gather(ctx.grid, points[k], ctx.scales.radius, &win);
    const CurveFit fit = FitCurve(&win, Eigen::Vector2d::Zero(), ctx.scales);
    // No vertex from an isolated point (noise), a fit that passes the anchor by (a corner cut
    // short) or one through a sixth of the points or less (a chord across a corner).
    const int least = std::max<int>(kMinSupport, static_cast<int>(win.size() / 6) + 1);
    if (!fit.ok || fit.support < least || std::abs(fit.a) > fit.tol) continue;
    for (size_t i = 0; i < win.d.size(); ++i) {
      if (std::abs(fit.t.dot(win.d[i])) <= reach && std::abs(fit.Residual(win.d[i])) <= fit.tol) {
        covered[win.slot[i]] = 1;
      }
    }
    vertices.push_back(
        {points[k] + fit.Offset(0), fit.Tangent(0), {fit.reach_ahead, fit.reach_behind}});
  }
  return vertices;
}

}  // namespace candi::section::lines_internal
