// candi relief place CORRESPONDENCES.csv -o placements.json [--panels DIR|FILES --points-out DIR]:
// each panel's world_from_panel by a robust rigid (or Sim3) fit of its corners / edge points to
// their documented positions on the foot wall (reconstruction/relief/relief_place.h), a table of
// residuals per panel, the placements as JSON and, optionally, the panels' points in world
// coordinates (double, in the integer shift of the documented positions). A panel that does not
// fit is a warning (exit 0); bad input is an error (exit 2) and writes nothing.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "apps/relief.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/georef/georef.h"
#include "reconstruction/relief/relief_place.h"

namespace candi::apps {

namespace {

namespace fs = std::filesystem;
namespace pg = candi::photogrammetry;
using nlohmann::json;
using relief::PanelPlacement;

constexpr size_t kChunk = 1 << 20;


bool IsPointFileName(const fs::path& p) {
  static const std::set<std::string> kExtensions = {".ply", ".las", ".xyz", ".pts", ".txt", ".asc"};
  std::string ext = p.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return kExtensions.count(ext) > 0;
}

// Panel id -> point file: listed files must be named <panel>.<ext> after a panel of the CSV;
// folders contribute their point files named after a panel (other files are ignored).
std::map<std::string, std::string> PanelFiles(const std::vector<std::string>& inputs,
                                              const std::set<std::string>& panels,
                                              const std::string& csv) {
  std::map<std::string, std::string> files;
  auto add = [&](const fs::path& p) {
    const std::string id = p.stem().string();
    const auto [it, added] = files.emplace(id, p.string());
    if (!added) throw InputError(p.string(), "", "panel '" + id + "' also has the file " + it->second);
    io::DetectPointFormat(p.string());  // readable and a point file, before the work
  };
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (!fs::is_directory(in, ec)) {
      if (!panels.count(fs::path(in).stem().string())) {
        throw InputError(in, "", "no panel '" + fs::path(in).stem().string() + "' in " + csv +
                                     " (a panel's points are named <panel>.ply)");
      }
      add(in);
      continue;
    }
    std::vector<fs::path> found;
    for (const auto& e : fs::directory_iterator(in)) {
      if (e.is_regular_file() && IsPointFileName(e.path()) && panels.count(e.path().stem().string())) {
        found.push_back(e.path());
      }
    }
    if (found.empty()) throw InputError(in, "", "folder holds no point file named after a panel of " + csv);
    std::sort(found.begin(), found.end());
    for (const fs::path& p : found) add(p);
  }
  return files;
}

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

void PrintTable(const relief::PlacementResult& r) {
  std::printf("%-16s %6s %7s %9s %9s %7s  %s\n", "panel", "points", "inliers", "RMS mm", "max mm",
              "scale", "status");
  for (const PanelPlacement& p : r.panels) {
    std::printf("%-16s %6zu %7d %9s %9s %7s  %s\n", p.panel.c_str(), p.correspondences.size(),
                p.inliers, Fixed(p.rms_mm, 2).c_str(), Fixed(p.max_mm, 2).c_str(),
                Fixed(p.world_from_panel.scale, 4).c_str(), p.status.c_str());
  }
  std::printf("\n%zu panels, %d fit, %d do not; shift %s\n", r.panels.size(),
              static_cast<int>(r.panels.size()) - r.misfits, r.misfits, r.frame.ToString().c_str());
}

json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json PanelJson(const PanelPlacement& p, const LocalFrame& frame, const std::string& points_file) {
  const Sim3& t = p.world_from_panel;
  const Eigen::Matrix4d m = t.ToMatrix();
  json matrix = json::array();
  for (int i = 0; i < 4; ++i) matrix.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  json j = {{"panel", p.panel},
            {"status", p.status},
            {"fits", p.fits},
            {"world_from_panel", {{"matrix", matrix},
                                  {"scale", t.scale},
                                  {"quaternion_wxyz", {t.rotation.w(), t.rotation.x(), t.rotation.y(), t.rotation.z()}},
                                  {"translation", Vec(t.translation)},
                                  {"local_translation", Vec(t.translation - frame.origin)}}},
            {"rms_mm", p.rms_mm},
            {"max_mm", p.max_mm},
            {"inliers", p.inliers},
            {"collinearity", p.collinearity},
            {"planarity", p.planarity},
            {"converged", p.converged},
            {"warnings", p.warnings}};
  if (!points_file.empty()) j["points"] = points_file;
  j["correspondences"] = json::array();
  for (size_t i = 0; i < p.correspondences.size(); ++i) {
    const Eigen::Vector3d& d = p.residuals_mm[i];
    j["correspondences"].push_back({{"point", p.correspondences[i].point},
                                    {"line", p.correspondences[i].line},
                                    {"residual_mm", Vec(d)},
                                    {"distance_mm", d.norm()},
                                    {"outlier", static_cast<bool>(p.outlier[i])}});
  }
  return j;
}

// Streams a panel's points into world coordinates, in the shift `frame` (positions in double).
void TransformPanel(const std::string& in, const Sim3& world_from_panel, const LocalFrame& frame,
                    const std::string& out) {
  auto reader = io::OpenPointReader(in);
  io::PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  spec.frame = frame;
  spec.count = reader->info().count;
  io::PointWriteOptions options;
  options.precision = io::PositionPrecision::kFloat64;
  auto writer = io::OpenPointWriter(out, spec, options);
  PointCloud chunk;
  while (reader->Read(kChunk, &chunk) > 0) {
    pg::ApplySimilarity(world_from_panel, frame, &chunk);
    writer->Write(chunk);
  }
  writer->Close();
}

}  // namespace

int RunReliefPlace(const ReliefPlaceArgs& args) {
  const relief::PanelPlacementOptions& options = args.options;
  options.Check();  // bad values: exit 1
  if (args.points_out.empty() != args.panels.empty()) {
    throw std::invalid_argument("--panels (the panels' point files) and --points-out (where they go "
                                "in world coordinates) go together");
  }
  CheckOutputFolder(args.output);
  const std::vector<relief::PanelCorrespondence> c = relief::ReadPanelCorrespondences(args.correspondences);
  std::set<std::string> ids;
  for (const relief::PanelCorrespondence& x : c) ids.insert(x.panel);
  const std::map<std::string, std::string> files = PanelFiles(args.panels, ids, args.correspondences);
  if (!args.points_out.empty()) {
    std::error_code ec;
    fs::create_directories(args.points_out, ec);
    if (ec || !fs::is_directory(args.points_out)) {
      throw InputError(args.points_out, "", "cannot create the output folder");
    }
    CheckOutputFolder(args.points_out + "/x.ply");
  }
  const relief::PlacementResult r = relief::PlacePanels(options, c, args.correspondences);
  PrintTable(r);
  for (const PanelPlacement& p : r.panels) {
    for (const std::string& w : p.warnings) LogWarning("panel '" + p.panel + "': " + w);
  }
  json j = {{"correspondences", args.correspondences},
            {"fit", options.estimate_scale ? "sim3" : "rigid"},
            {"loss", pg::RobustLossName(options.loss)},
            {"loss_scale_m", options.loss_scale},
            {"default_accuracy_m", options.default_accuracy},
            {"tolerance_mm", options.tolerance_mm},
            {"shift", Vec(r.frame.origin)},
            {"panel_count", r.panels.size()},
            {"misfits", r.misfits},
            {"panels", json::array()}};
  std::map<std::string, std::string> written;  // panel -> its points in world coordinates
  if (!args.points_out.empty()) {
    ConsoleProgressOptions po;
    po.unit = "panels";
    ConsoleProgress progress("panels to world coordinates", po);
    for (const PanelPlacement& p : r.panels) {
      const auto file = files.find(p.panel);
      if (file == files.end()) continue;
      const std::string out = args.points_out + "/" + p.panel + ".ply";
      TransformPanel(file->second, p.world_from_panel, r.frame, out);
      written[p.panel] = out;
      progress.Update(written.size(), files.size());
    }
  }
  for (const PanelPlacement& p : r.panels) {
    const auto out = written.find(p.panel);
    j["panels"].push_back(PanelJson(p, r.frame, out == written.end() ? "" : out->second));
  }
  if (!args.points_out.empty()) {
    LogInfo("wrote " + std::to_string(written.size()) + " panels in world coordinates to " + args.points_out);
  }
  WriteFileAtomic(args.output, j.dump(2) + "\n");
  if (r.misfits > 0) {
    LogWarning(std::to_string(r.misfits) + " of " + std::to_string(r.panels.size()) +
               " panels do not fit their documented positions (see the table and " + args.output + ")");
  }
  return kOk;  // panels that do not fit are reported (table, JSON, warnings), not an error
}

}  // namespace candi::apps
