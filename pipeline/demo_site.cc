#include "pipeline/demo_site.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/rng.h"
#include "core/transform.h"
#include "io/point_io.h"
#include "pipeline/relief.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

// Geometry of the stand-in (metres; x east, y north, z up; the base's centre at the origin).
constexpr double kBaseHalf = 56.5;        // 113 m square base: the original foot wall
constexpr double kEncasementHalf = 60.0;  // the encasement's outer face
constexpr double kFootHeight = 4.0;       // the foot (and the encasement) top
// The excavated southeast corner: the encasement removed over x in [kDigX0, kEncasementHalf] on
// the south side, exposing the foot wall (and its panels) there.
constexpr double kDigX0 = 44.8;  // between panels 36 and 37 of the south side (k = 35, 36)

struct Sampler {
  PointCloud* cloud;
  Rng rng;
  double density;  // points per m^2

  size_t Count(double area) {
    const double n = density * area;
    size_t k = static_cast<size_t>(n);
    if (rng.Uniform() < n - static_cast<double>(k)) ++k;
    return k;
  }
  void Add(const Eigen::Vector3d& p, double shade) {
    const double g = std::clamp(shade * (0.86 + 0.14 * rng.Uniform()), 0.0, 1.0);
    cloud->positions.push_back(p);
    cloud->colors.push_back({static_cast<uint8_t>(150 * g + 45), static_cast<uint8_t>(140 * g + 40),
                             static_cast<uint8_t>(118 * g + 32)});
  }
  // An axis-aligned rectangle: origin + s u + t v, s, t in [0, 1]; `keep` filters points.
  template <typename Keep>
  void Rect(const Eigen::Vector3d& o, const Eigen::Vector3d& u, const Eigen::Vector3d& v, double shade, Keep keep) {
    const size_t n = Count(u.norm() * v.norm());
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p = o + rng.Uniform() * u + rng.Uniform() * v;
      if (keep(p)) Add(p, shade);
    }
  }
  void Rect(const Eigen::Vector3d& o, const Eigen::Vector3d& u, const Eigen::Vector3d& v, double shade) {
    Rect(o, u, v, shade, [](const Eigen::Vector3d&) { return true; });
  }
  // The four vertical faces of a square of half-size a between z0 and z1, and optionally the ring
  // on top between half-sizes inner and a.
  template <typename Keep>
  void SquareWalls(double a, double z0, double z1, Keep keep) {
    const double h = z1 - z0;
    const double shades[4] = {0.75, 0.95, 0.6, 0.8};  // south east north west: a light from the east
    Rect({-a, -a, z0}, {2 * a, 0, 0}, {0, 0, h}, shades[0], keep);
    Rect({a, -a, z0}, {0, 2 * a, 0}, {0, 0, h}, shades[1], keep);
    Rect({-a, a, z0}, {2 * a, 0, 0}, {0, 0, h}, shades[2], keep);
    Rect({-a, -a, z0}, {0, 2 * a, 0}, {0, 0, h}, shades[3], keep);
  }
  template <typename Keep>
  void SquareRing(double a, double inner, double z, Keep keep) {
    const size_t n = Count(4 * (a * a - inner * inner));
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p(rng.Uniform(-a, a), rng.Uniform(-a, a), z);
      if (std::max(std::abs(p.x()), std::abs(p.y())) >= inner && keep(p)) Add(p, 1.0);
    }
  }
  void Cylinder(double r, double z0, double z1) {
    const size_t n = Count(2 * kPi * r * (z1 - z0));
    for (size_t i = 0; i < n; ++i) {
      const double phi = rng.Uniform(0, 2 * kPi);
      Add({r * std::cos(phi), r * std::sin(phi), rng.Uniform(z0, z1)}, 0.7 + 0.25 * std::cos(phi));
    }
  }
  void Disc(double r, double inner, double z) {
    const size_t n = Count(kPi * (r * r - inner * inner));
    for (size_t i = 0; i < n; ++i) {
      const double phi = rng.Uniform(0, 2 * kPi), rr = std::sqrt(rng.Uniform(inner * inner, r * r));
      Add({rr * std::cos(phi), rr * std::sin(phi), z}, 1.0);
    }
  }
  // A bell-shaped stupa at `base`: a half ellipsoid of radius r and height h; perforated ones have
  // diamond openings (points removed in a lattice), as the 72 on the circular terraces do.
  void Stupa(const Eigen::Vector3d& base, double r, double h, bool perforated) {
    const size_t n = Count(2 * kPi * r * std::max(r, h));
    for (size_t i = 0; i < n; ++i) {
      const double phi = rng.Uniform(0, 2 * kPi), c = rng.Uniform(0, 1), s = std::sqrt(1 - c * c);
      if (perforated && c < 0.7) {
        const double a = phi * 16 / (2 * kPi), b = c * 8;
        const double fa = a - std::floor(a) - 0.5, fb = b - std::floor(b) - 0.5;
        if (std::abs(fa) + std::abs(fb) < 0.28) continue;  // an opening
      }
      Add(base + Eigen::Vector3d(r * s * std::cos(phi), r * s * std::sin(phi), h * c),
          0.55 + 0.3 * c + 0.15 * std::cos(phi));
    }
    const size_t spire = Count(2 * kPi * 0.15 * r * 0.5 * h);
    for (size_t i = 0; i < spire; ++i) {
      const double phi = rng.Uniform(0, 2 * kPi);
      Add(base + Eigen::Vector3d(0.15 * r * std::cos(phi), 0.15 * r * std::sin(phi), h * rng.Uniform(1.0, 1.5)), 0.8);
    }
  }
};

PointCloud Building(uint64_t seed, double density) {
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.SetSchema(cloud.schema);
  Sampler s{&cloud, Rng(seed), density};
  auto all = [](const Eigen::Vector3d&) { return true; };
  // The foot and the encasement at 10x the density (the close-range scan of the lowest 4 m): the
  // corner close-ups must be watertight, or hidden panels would show through the gaps.
  Sampler foot{&cloud, Rng(seed + 1), 10 * density};
  // The encasement: outer faces (with the southeast dig cut out), its top, and the dig's floor
  // and side face; the original foot wall shows only inside the dig.
  const double e = kEncasementHalf, a0 = kBaseHalf;
  foot.SquareWalls(e, 0, kFootHeight, [&](const Eigen::Vector3d& p) {
    return !(p.y() <= -e + 1e-9 && p.x() >= kDigX0);
  });
  foot.SquareRing(e, a0, kFootHeight, [&](const Eigen::Vector3d& p) { return !(p.x() >= kDigX0 && p.y() <= -a0); });
  foot.Rect({kDigX0, -e, 0}, {0, e - a0, 0}, {0, 0, kFootHeight}, 0.9);          // the dig's west face
  foot.Rect({kDigX0, -e, 0}, {e - kDigX0, 0, 0}, {0, e - a0, 0}, 0.5);            // the dig's floor
  foot.Rect({e, -e, 0}, {0, e - a0, 0}, {0, 0, kFootHeight}, 0.95);               // east face end
  foot.Rect({kDigX0, -a0, 0}, {a0 - kDigX0, 0, 0}, {0, 0, kFootHeight}, 0.8);     // the exposed foot
  // Five more square platforms with balustrades (galleries), then three circular terraces.
  double z = kFootHeight;
  for (int k = 1; k < 6; ++k) {
    const double a = a0 - 5.5 * k, h = 3.4;
    s.SquareWalls(a, z, z + h, all);
    const double next = k < 5 ? a0 - 5.5 * (k + 1) : 25.5;
    s.SquareRing(a, next, z + h, all);
    s.SquareWalls(a - 0.3, z + h, z + h + 1.2, all);  // the balustrade
    z += h;
  }
  const double rings[3] = {25.0, 19.5, 14.0};
  const int stupas[3] = {32, 24, 16};
  for (int k = 0; k < 3; ++k) {
    const double r = rings[k] + 2.6, h = 1.3;
    s.Cylinder(r, z, z + h);
    s.Disc(r, k < 2 ? rings[k + 1] + 2.6 : 6.0, z + h);
    z += h;
    for (int j = 0; j < stupas[k]; ++j) {
      const double phi = 2 * kPi * (j + 0.5 * k) / stupas[k];
      s.Stupa({rings[k] * std::cos(phi), rings[k] * std::sin(phi), z}, 1.6, 3.2, true);
    }
  }
  s.Stupa({0, 0, z}, 8.0, 8.5, false);  // the central stupa; its spire reaches ~35 m
  cloud.CheckConsistent();
  return cloud;
}

json Camera(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, double fov, int w, int h) {
  return {{"projection", "perspective"}, {"eye", {eye.x(), eye.y(), eye.z()}},
          {"target", {target.x(), target.y(), target.z()}}, {"up", {0, 0, 1}}, {"fov_y_deg", fov},
          {"width", w}, {"height", h}};
}

// The Karmawibhangga panels on the original foot wall: 40 a side (south, east, north, west), 2.7 x
// 0.92 m, 2.8 m apart, bottoms 0.8 m above the foot. Panel k's frame (relief_points.h: x along the
// wall left to right seen from outside, y up, z out) in world coordinates.
constexpr double kPanelWidth = 2.7, kPanelHeight = 0.92;
Sim3 WorldFromPanel(int k) {
  const double angle = (k / 40) * kPi / 2;  // south, east, north, west
  const Eigen::Vector3d n(std::sin(angle), -std::cos(angle), 0);  // outward normal
  const Eigen::Vector3d along = Eigen::Vector3d::UnitZ().cross(n);
  const double t = -kBaseHalf + 0.5 + 2.8 * (k % 40) + 0.05;
  Eigen::Matrix3d r;
  r.col(0) = along, r.col(1) = Eigen::Vector3d::UnitZ(), r.col(2) = n;
  return Sim3(1.0, Eigen::Quaterniond(r), kBaseHalf * n + t * along + Eigen::Vector3d(0, 0, 0.8));
}
// Visible: in the excavated southeast corner (the last four of the south side).
bool PanelVisible(int k) { return k / 40 == 0 && WorldFromPanel(k).translation.x() >= kDigX0; }

// The documented positions: four corners and two mid-edge points per panel, surveyed to 1 mm.
std::string PanelPositionsCsv(const std::vector<int>& panels, uint64_t seed) {
  Rng rng(seed ^ 0x9e3779b97f4a7c15ull);
  std::string csv = "panel,point,x,y,z,E,N,H,accuracy\n";
  const Eigen::Vector3d points[6] = {{0, 0, 0}, {kPanelWidth, 0, 0}, {kPanelWidth, kPanelHeight, 0},
                                     {0, kPanelHeight, 0}, {kPanelWidth / 2, 0, 0}, {kPanelWidth / 2, kPanelHeight, 0}};
  const char* names[6] = {"bottom_left", "bottom_right", "top_right", "top_left", "bottom_mid", "top_mid"};
  for (int k : panels) {
    const Sim3 t = WorldFromPanel(k);
    for (int j = 0; j < 6; ++j) {
      const Eigen::Vector3d w = t * points[j] + 0.001 * Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
      char line[256];
      std::snprintf(line, sizeof(line), "P%03d,%s,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,0.002\n", k + 1, names[j],
                    points[j].x(), points[j].y(), points[j].z(), w.x(), w.y(), w.z());
      csv += line;
    }
  }
  return csv;
}

// The close-range survey of the excavated southeast corner. The solid model matches the stand-in
// (Building) there: the ground, the encasement with the dig, the original foot wall behind it, the
// thin east end of the dig, the two lowest platforms and a balustrade; eight targets painted on
// the surfaces (their centres lie on them).
photogrammetry::SyntheticScene CornerScene() {
  using photogrammetry::SyntheticBox;
  photogrammetry::SyntheticScene s;
  const Eigen::Vector3d stone(0.86, 0.79, 0.66), soil(0.70, 0.62, 0.50);
  const double e = kEncasementHalf, a0 = kBaseHalf, h = kFootHeight;
  s.solids = {SyntheticBox({20, -95, -1}, {100, -20, 0}, soil),               // the ground
              SyntheticBox({20, -e, 0}, {kDigX0, -20, h}, stone),             // the encasement west of the dig
              SyntheticBox({kDigX0, -a0, 0}, {e, -20, h}, stone),             // the foot and the encasement east
              SyntheticBox({e - 0.2, -e, 0}, {e, -a0, h}, stone),             // the dig's east end
              SyntheticBox({20, -51, h}, {51, -20, h + 3.4}, stone),          // first platform
              SyntheticBox({20, -50.7, h + 3.4}, {50.7, -20, h + 4.6}, stone),  // its balustrade
              SyntheticBox({20, -45.5, h + 3.4}, {45.5, -20, h + 6.8}, stone)};  // second platform
  s.light = Eigen::Vector3d(0.55, -0.5, 0.67).normalized();  // morning sun from the south-east
  s.markers = {{"T1", {46.0, -a0, 3.5}, 0.15},  {"T2", {55.5, -a0, 3.5}, 0.15}, {"T3", {50.0, -58.8, 0}, 0.15},
               {"T4", {57.5, -59.0, 0}, 0.15},  {"T5", {40.0, -e, 2.5}, 0.15},   {"T6", {43.0, -e, 1.0}, 0.15},
               {"T7", {45.0, -62.5, 0}, 0.15},  {"T8", {58.0, -62.5, 0}, 0.15}};
  return s;
}

// Renders the corner photos into DIR/photos and writes the targets' surveyed coordinates (1 mm
// noise; T3 and T8 are check targets) and where they are picked in the photos (0.3 px noise).
struct CornerSurvey {
  std::string photos, targets, picks;
  int count = 0, width = 0, height = 0;
};
CornerSurvey SurveyCorner(const fs::path& dir, bool quick, uint64_t seed) {
  const photogrammetry::SyntheticScene scene = CornerScene();
  CornerSurvey c;
  c.count = quick ? 8 : 10;
  c.width = quick ? 360 : 480;
  c.height = c.width * 3 / 4;
  std::vector<photogrammetry::PinholeCamera> cameras;
  for (int k = 0; k < c.count; ++k) {  // a walk along the dig, 8 m in front of the encasement
    const double x = 38.0 + 26.0 * k / (c.count - 1);
    cameras.push_back(photogrammetry::LookAtCamera({x, -68.0, 2.2 + 0.4 * (k % 2)},
                                                   {0.8 * x + 0.2 * 52.4, -57.0, 1.6}, c.width, c.height, 62));
  }
  photogrammetry::SyntheticViewsOptions o;
  o.texture_cell = 0.07;
  o.supersample = 2;
  o.seed = seed;
  o.name_prefix = "corner";
  const std::vector<photogrammetry::SyntheticView> views = photogrammetry::RenderSyntheticScene(scene, cameras, o);
  c.photos = (dir / "photos").string();
  photogrammetry::WriteSyntheticImages(views, c.photos);
  Rng rng(seed ^ 0x7a26e75ull);
  std::string targets = "name,E,N,H,role,accuracy\n", picks = "name,image,u,v\n";
  char line[256];
  for (const photogrammetry::SyntheticMarker& m : scene.markers) {
    const Eigen::Vector3d p = m.center + 0.001 * Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
    const bool check = m.name == "T3" || m.name == "T8";
    std::snprintf(line, sizeof(line), "%s,%.4f,%.4f,%.4f,%s,0.002\n", m.name.c_str(), p.x(), p.y(), p.z(),
                  check ? "check" : "control");
    targets += line;
    for (const photogrammetry::SyntheticView& v : views) {
      if (!scene.Sees(v.camera, m.center)) continue;
      const Eigen::Vector2d uv = v.camera.Project(v.camera.ToCamera(m.center));
      const double margin = 8;
      if (uv.x() < margin || uv.y() < margin || uv.x() > c.width - margin || uv.y() > c.height - margin) continue;
      std::snprintf(line, sizeof(line), "%s,%s,%.2f,%.2f\n", m.name.c_str(), v.name.c_str(),
                    uv.x() + 0.3 * rng.Normal(), uv.y() + 0.3 * rng.Normal());
      picks += line;
    }
  }
  c.targets = (dir / "targets.csv").string();
  c.picks = (dir / "picks.csv").string();
  WriteFileAtomic(c.targets, targets);
  WriteFileAtomic(c.picks, picks);
  return c;
}

}  // namespace

void DemoSiteOptions::Check() const {
  CANDI_CHECK_OPTION_IN(width, 16, 16384);
  CANDI_CHECK_OPTION_IN(height, 16, 16384);
  CANDI_CHECK_OPTION(!(quick && full), full, "false with quick (they exclude each other)");
}

std::string MakeDemoSite(const DemoSiteOptions& options, const std::string& output_dir) {
  options.Check();
  const fs::path out = fs::absolute(output_dir).lexically_normal();
  std::error_code ec;
  fs::create_directories(out / "inputs", ec);
  if (ec) throw InputError(output_dir, "", "cannot create the output folder: " + ec.message());
  const double density = options.quick ? 10.0 : 40.0;
  LogInfo("candi demo: the bundled Borobudur example (building: a procedural stand-in for the scan, "
          "which is not public; foundation: examples/borobudur/foundation.dxf)");
  const PointCloud building = Building(options.seed, density);
  const std::string building_ply = (out / "inputs" / "building.ply").string();
  io::WritePointCloud(building_ply, building);
  LogInfo("building: " + std::to_string(building.size()) + " points");

  const std::string source_dir = options.source_dir.empty() ? CANDI_SOURCE_DIR : options.source_dir;
  const int w = options.width, h = options.height;
  json building_layer = {{"name", "building"}, {"kind", "points"}, {"file", building_ply}, {"opacity", 0.25}};
  json foundation_layer = {{"name", "foundation"}, {"kind", "foundation"},
                           {"dxf", source_dir + "/examples/borobudur/foundation.dxf"},
                           {"count", options.quick ? 200000 : 4470000}, {"opacity", 0.6},
                           {"samples_per_side", options.quick ? 200 : 1000}, {"angular_steps", options.quick ? 36 : 90}};
  // The reliefs: one synthetic old photo per panel (relief synth), through the shipped model.
  std::vector<int> panels;
  for (int k = 0; k < 160; ++k)
    if (!options.quick || (k / 40 == 0 && k % 40 >= 28)) panels.push_back(k);  // quick: 8 hidden + 4 visible
  relief::SynthOptions synth;
  synth.width = 270;
  synth.seed = options.seed;
  const std::string panel_dir = (out / "inputs" / "panels").string();
  WriteSyntheticPanels(synth, static_cast<int>(panels.size()), panel_dir);
  const std::string positions_csv = (out / "inputs" / "panel_positions.csv").string();
  WriteFileAtomic(positions_csv, PanelPositionsCsv(panels, options.seed));
  json panel_list = json::array();
  for (size_t i = 0; i < panels.size(); ++i) {
    char id[16], photo[48];
    std::snprintf(id, sizeof(id), "P%03d", panels[i] + 1);
    std::snprintf(photo, sizeof(photo), "panel_%04zu_photo.png", i);
    json panel = {{"id", id}, {"photo", (fs::path(panel_dir) / photo).string()}};
    // Reduced to fit the demo's time: the hidden panels, seen only through the encasement, go
    // through the network at their photos' own resolution, not resampled to the model's (3 tiles
    // each, not 24).
    if (!options.full && !PanelVisible(panels[i])) panel["native_resolution"] = true;
    panel_list.push_back(panel);
  }
  json reliefs_layer = {{"name", "reliefs"}, {"kind", "relief"}, {"panels", panel_list},
                        {"model", source_dir + "/examples/relief/relief_model.pt"}, {"placement", positions_csv},
                        {"width_m", kPanelWidth}, {"opacity", 0.9}, {"highlight", true}};
  LogInfo(std::to_string(panels.size()) + " relief panels (" +
          std::to_string(std::count_if(panels.begin(), panels.end(), PanelVisible)) + " visible in the dig)");
  // The close range: the excavated corner through sfm + dense, over the coarse scan. Reduced to
  // fit the demo's time: 10 photos of 480x360, 1024 SIFT features each, two PatchMatch rounds at
  // 0.75 of the photos' resolution (quick: 8 photos of 360x270, stereo at half resolution).
  const CornerSurvey survey = SurveyCorner(out / "inputs" / "corner", options.quick, options.seed);
  json corner_layer = {{"name", "corner"}, {"kind", "photogrammetry"}, {"images", survey.photos},
                       {"targets", survey.targets}, {"picks", survey.picks}, {"max_image_size", survey.width},
                       {"max_features", 1024}, {"resolution_scale", options.quick ? 0.5 : 0.75}, {"iterations", 2},
                       {"opacity", 0.25},
                       {"replaces", {"building"}}, {"replace_voxel", 0.5}};
  LogInfo("close range: " + std::to_string(survey.count) + " photos of the excavated corner, " +
          std::to_string(survey.width) + "x" + std::to_string(survey.height));
  json scene = {{"candi_scene", 1}, {"name", "borobudur"}, {"seed", options.seed}};
  scene["render"] = {{"repeat_level", options.quick ? 32 : 100}, {"width", w}, {"height", h},
                     {"background", {255, 255, 255}}};
  scene["layers"] = json::array({building_layer, foundation_layer, reliefs_layer, corner_layer});
  const json overview = Camera({170, -230, 110}, {0, 0, -5}, 38, w, h);
  // The southeast corner close up: the building, the close range and the reliefs, not the hill
  // around it; and the same without the reliefs, so the panels' share of each image can be measured. Opaque close-ups use 3-px
  // points so that no gap lets a hidden panel through; see-through ones keep 1-px points, for
  // which the opacity law holds.
  const json corner_layers = json::array({"building", "corner", "reliefs"});
  const json building_only = json::array({"building", "corner"});
  const json corner = Camera({72, -84, 6}, {44, -56.5, 1.5}, 40, w, h);
  scene["views"] = {{{"name", "overview_opaque"}, {"camera", overview}, {"opaque", true}},
                    {{"name", "overview_transparent"}, {"camera", overview}},
                    {{"name", "corner_opaque"}, {"camera", corner}, {"opaque", true}, {"layers", corner_layers}, {"point_size", 3}},
                    {{"name", "corner_transparent"}, {"camera", corner}, {"layers", corner_layers}},
                    {{"name", "corner_panels"}, {"camera", corner}, {"layers", corner_layers}, {"focus", true}, {"dim", 0.4}},
                    {{"name", "corner_opaque_building"}, {"camera", corner}, {"opaque", true}, {"layers", building_only}, {"point_size", 3}},
                    {{"name", "corner_transparent_building"}, {"camera", corner}, {"layers", building_only}}};
  const std::string scene_file = (out / "scene.json").string();
  WriteFileAtomic(scene_file, scene.dump(2) + "\n");
  return scene_file;
}

}  // namespace candi::pipeline
