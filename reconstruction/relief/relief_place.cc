#include "reconstruction/relief/relief_place.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>

#include "core/box.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/csv_table.h"

namespace candi::relief {

namespace {

namespace pg = candi::photogrammetry;

std::string Line(int line) { return line > 0 ? "line " + std::to_string(line) : ""; }

// Indices of the correspondences of each panel, panels in order of first appearance.
std::vector<std::vector<size_t>> GroupByPanel(const std::vector<PanelCorrespondence>& c) {
  std::map<std::string, size_t> index;
  std::vector<std::vector<size_t>> groups;
  for (size_t i = 0; i < c.size(); ++i) {
    const auto [it, added] = index.emplace(c[i].panel, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(i);
  }
  return groups;
}

// Every panel has >= 3 correspondences, not all at one point, and unique point names.
void CheckPanels(const std::vector<PanelCorrespondence>& c, const std::string& source) {
  for (const std::vector<size_t>& g : GroupByPanel(c)) {
    const PanelCorrespondence& first = c[g.front()];
    if (g.size() < 3) {
      throw InputError(source, Line(first.line),
                       "panel '" + first.panel + "' has " + std::to_string(g.size()) +
                           " correspondence(s); a placement needs at least 3 (not collinear)");
    }
    std::set<std::string> names;
    double spread = 0;
    for (size_t i : g) {
      if (!names.insert(c[i].point).second) {
        throw InputError(source, Line(c[i].line), "field 'point': '" + c[i].point +
                                                      "' appears twice on panel '" + first.panel + "'");
      }
      spread = std::max(spread, (c[i].in_panel - first.in_panel).norm());
    }
    if (!(spread > 0)) {
      throw InputError(source, Line(first.line), "panel '" + first.panel +
                                                     "': all its panel points coincide; no placement is determined");
    }
  }
}

PanelCorrespondence ParseRow(const io::CsvTable& t, const io::CsvTable::Row& row) {
  PanelCorrespondence c;
  c.line = row.line;
  c.panel = t.Text(row, "panel");
  c.point = t.Text(row, "point");
  if (c.panel.empty()) t.Fail(row, "panel", "empty");
  if (c.point.empty()) t.Fail(row, "point", "empty");
  c.in_panel = Eigen::Vector3d(t.Number(row, "x"), t.Number(row, "y"), t.Number(row, "z"));
  c.in_world = Eigen::Vector3d(t.Number(row, "E"), t.Number(row, "N"), t.Number(row, "H"));
  if (t.Has("accuracy") && !t.Text(row, "accuracy").empty()) {
    c.accuracy = t.Number(row, "accuracy");
    if (!(c.accuracy > 0)) t.Fail(row, "accuracy", t.Text(row, "accuracy") + "; must be > 0 m");
  }
  return c;
}

const std::vector<std::string> kColumns = {"panel", "point", "x", "y", "z", "E", "N", "H"};

std::vector<PanelCorrespondence> FromTable(const io::CsvTable& t) {
  std::vector<PanelCorrespondence> out;
  for (const io::CsvTable::Row& row : t.rows()) out.push_back(ParseRow(t, row));
  if (out.empty()) throw InputError(t.path(), "", "no correspondences (only a header)");
  CheckPanels(out, t.path());
  return out;
}

PanelPlacement PlaceOne(const PanelPlacementOptions& o, const std::vector<PanelCorrespondence>& all,
                        const std::vector<size_t>& group, const std::string& source) {
  PanelPlacement p;
  p.panel = all[group.front()].panel;
  std::vector<Eigen::Vector3d> x, y;
  std::vector<double> accuracy;
  for (size_t i : group) {
    p.correspondences.push_back(all[i]);
    x.push_back(all[i].in_panel);
    y.push_back(all[i].in_world);
    accuracy.push_back(all[i].accuracy > 0 ? all[i].accuracy : o.default_accuracy);
  }
  pg::SimilarityFitOptions fit;
  fit.estimate_scale = o.estimate_scale;
  fit.loss = o.loss;
  fit.loss_scale = o.loss_scale;
  fit.outlier_k = o.outlier_k;
  fit.collinear_ratio = o.collinear_ratio;
  // A panel's points lie on (or within 0.15 m of) the wall plane by nature; a planar layout still
  // fixes the full rotation, and nothing is extrapolated far from the plane: the fit's coplanar
  // warning is dropped below (planarity stays in the result).
  pg::SimilarityFitResult r;
  try {
    r = pg::FitSimilarity(fit, x, y, accuracy);
  } catch (const std::invalid_argument& e) {  // coincident points, non-finite input
    throw InputError(source, Line(p.correspondences.front().line),
                     "panel '" + p.panel + "': " + e.what());
  }
  p.world_from_panel = r.target_from_source;
  p.outlier = r.outlier;
  p.inliers = r.inliers;
  p.collinearity = r.collinearity;
  p.planarity = r.planarity;
  p.converged = r.converged;
  p.solver_message = r.solver_message;
  for (const std::string& w : r.warnings) {
    // A panel's points lie on (or within 0.15 m of) the wall plane by nature: see above.
    if (w.rfind("targets nearly coplanar", 0) != 0) p.warnings.push_back(w);
  }
  double sum2 = 0;
  for (size_t i = 0; i < r.residuals.size(); ++i) {
    p.residuals_mm.push_back(1000.0 * r.residuals[i]);
    if (r.outlier[i] && r.inliers < static_cast<int>(r.residuals.size())) continue;
    const double d = 1000.0 * r.residuals[i].norm();
    sum2 += d * d;
    p.max_mm = std::max(p.max_mm, d);
  }
  p.rms_mm = std::sqrt(sum2 / std::max(1, p.inliers));
  int flagged = 0;
  for (size_t i = 0; i < p.outlier.size(); ++i) {
    if (!p.outlier[i]) continue;
    ++flagged;
    p.warnings.push_back(
        "correspondence '" + p.correspondences[i].point + "' (" +
        (p.correspondences[i].line > 0 ? Line(p.correspondences[i].line) : "built in code") +
        ") is an outlier: residual " + FormatSignificant(1000 * r.residuals[i].norm(), 4) + " mm");
  }
  if (r.collinear) {
    p.status = "collinear";
  } else if (!r.converged) {
    p.status = "not converged";
  } else if (flagged > std::max(1.0, o.max_outlier_fraction * static_cast<double>(p.outlier.size()))) {
    // Many points that do not fit are the panel's shape disagreeing with the positions, not a few
    // misread positions: the fit to the rest would hide the misfit.
    p.status = "misfit";
    p.warnings.push_back("does not fit: " + std::to_string(flagged) + " of " +
                         std::to_string(p.outlier.size()) +
                         " correspondences are outliers (more than " +
                         FormatSignificant(100 * o.max_outlier_fraction, 4) + " %)");
  } else if (p.rms_mm > o.tolerance_mm) {
    p.status = "misfit";
    p.warnings.push_back("does not fit: RMS residual " + FormatSignificant(p.rms_mm, 4) +
                         " mm > tolerance " + FormatSignificant(o.tolerance_mm, 4) +
                         " mm (the documented positions do not match the panel's shape)");
  } else {
    p.status = "ok";
  }
  p.fits = p.status == "ok";
  return p;
}

}  // namespace

void PanelPlacementOptions::Check() const {
  CANDI_CHECK_OPTION(loss_scale > 0 && std::isfinite(loss_scale), loss_scale, "> 0");
  CANDI_CHECK_OPTION(default_accuracy > 0 && std::isfinite(default_accuracy), default_accuracy,
                     "> 0");
  CANDI_CHECK_OPTION(outlier_k > 0 && std::isfinite(outlier_k), outlier_k, "> 0");
  CANDI_CHECK_OPTION(tolerance_mm > 0 && std::isfinite(tolerance_mm), tolerance_mm, "> 0");
  CANDI_CHECK_OPTION(max_outlier_fraction >= 0 && max_outlier_fraction < 1, max_outlier_fraction,
                     "in [0, 1)");
  CANDI_CHECK_OPTION(collinear_ratio > 0 && collinear_ratio < 1, collinear_ratio, "in (0, 1)");
}

std::vector<PanelCorrespondence> ParsePanelCorrespondences(const std::string& path,
                                                           const std::string& text) {
  return FromTable(io::CsvTable::Parse(path, text, kColumns));
}

std::vector<PanelCorrespondence> ReadPanelCorrespondences(const std::string& path) {
  return FromTable(io::CsvTable::Read(path, kColumns));
}

PlacementResult PlacePanels(const PanelPlacementOptions& options,
                            const std::vector<PanelCorrespondence>& correspondences,
                            const std::string& source) {
  options.Check();
  if (correspondences.empty()) throw InputError(source, "", "no correspondences");
  CheckPanels(correspondences, source);
  PlacementResult result;
  Box3d world;
  for (const PanelCorrespondence& c : correspondences) world.Extend(c.in_world);
  result.frame = LocalFrame::Auto(world);
  for (const std::vector<size_t>& group : GroupByPanel(correspondences)) {
    result.panels.push_back(PlaceOne(options, correspondences, group, source));
    result.misfits += !result.panels.back().fits;
  }
  return result;
}

}  // namespace candi::relief
