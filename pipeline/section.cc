#include "pipeline/section.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/base64.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "core/version.h"
#include "io/layer_clouds.h"
#include "io/point_io.h"
#include "render/archive_clip.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"
#include "sampling/layer_colours.h"
#include "section/section_corners.h"
#include "section/section_dxf.h"
#include "section/section_lines.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
using section::SectionLayerResult;
using section::SectionPath;
using section::SectionWindow;

// The slab's points, per layer, in drawing coordinates.
struct Slab {
  std::vector<std::string> names;
  std::vector<std::vector<Eigen::Vector2d>> drawing;  // per layer
  std::vector<std::vector<float>> depth;              // per layer: signed distance from the plane
  std::vector<std::vector<Rgb8>> colours;             // per layer: the points' own colours
  uint64_t chunks = 0, chunks_read = 0, points_read = 0;
  bool archive = false;
  double read_s = 0, lines_s = 0, image_s = 0;  // stage timings
  std::vector<std::string> seen;                      // every layer name of the inputs (options.layers)

  size_t Layer(const std::string& name) {
    for (size_t k = 0; k < names.size(); ++k) {
      if (names[k] == name) return k;
    }
    names.push_back(name);
    drawing.emplace_back();
    depth.emplace_back();
    colours.emplace_back();
    return names.size() - 1;
  }
  void Add(size_t layer, const SectionPath& s, const Eigen::Vector3d& world, size_t segment, Rgb8 colour) {
    double d = 0;
    drawing[layer].push_back(s.ToDrawing(world, segment, &d));
    depth[layer].push_back(static_cast<float>(d));
    colours[layer].push_back(colour);
  }
};

// The segment a slab point belongs to: 0 for a plane; for a path the segment nearest in plan when
// its slab holds the point, else the first slab that does (`first_region`).
size_t SegmentOf(const SectionPath& s, const Eigen::Vector3d& world, size_t first_region) {
  if (!s.is_path()) return 0;
  const size_t nearest = s.NearestSegment(world);
  return s.regions()[nearest].Contains(world) ? nearest : first_region;
}

void ReadArchiveSlab(const SectionOptions& o, const std::string& dir, const SectionPath& s, const ClipRegion& clip,
                     Slab* slab) {
  const render::Archive archive(dir);
  const render::ArchiveManifest& m = archive.manifest();
  render::ClippedReadOptions read;
  read.threads = o.threads;
  if (!o.layers.empty()) {
    read.layers.assign(m.layers.size(), 0);
    for (const std::string& name : o.layers) {
      bool found = false;
      for (size_t k = 0; k < m.layers.size(); ++k) {
        if (m.layers[k].name == name) read.layers[k] = found = true;
      }
      if (!found) {
        std::string known;
        for (const auto& l : m.layers) known += (known.empty() ? "" : ", ") + l.name;
        throw std::invalid_argument("--layers: " + dir + " has no layer '" + name + "' (it has " + known + ")");
      }
    }
  }
  std::vector<ClipRegion> regions;
  for (const ClipRegion& r : s.regions()) regions.push_back(r.And(clip).ToLocal(m.frame.origin));
  for (size_t k = 0; k < m.layers.size(); ++k) {
    if (read.layers.empty() || read.layers[k]) slab->Layer(m.layers[k].name);
  }
  read.max_points = o.max_points;
  ConsoleProgress progress("section: reading the chunks the slab crosses");
  const ProgressCallback shown = progress.Callback();
  const render::ClippedPoints got = render::ReadClipped(read, archive, regions, [&](uint64_t done, uint64_t total) {
    if (o.checkpoint) o.checkpoint();
    shown(done, total);
  });
  progress.Finish();
  for (size_t i = 0; i < got.cloud.size(); ++i) {
    const Eigen::Vector3d world = got.cloud.WorldPosition(i);
    slab->Add(slab->Layer(m.layers[got.cloud.layers[i]].name), s, world, SegmentOf(s, world, got.region[i]),
              got.cloud.colors[i]);
  }
  slab->archive = true;
  slab->chunks = got.chunks;
  slab->chunks_read = got.chunks_read;
  slab->points_read = got.points_read;
}

void ReadFileSlab(const SectionOptions& o, const std::string& path, const SectionPath& s, const ClipRegion& clip,
                  Slab* slab) {
  io::PointReadOptions read;
  read.columns = o.columns;
  read.scalar_fields = false;
  auto reader = io::OpenPointReader(path, read);
  const std::string stem = fs::path(path).stem().string();
  const std::map<int, std::string> named = io::ReadLayerNames(reader->info().meta);
  std::unordered_map<int, size_t> layer_of;  // the file's layer id -> slab layer (kSkipped: not wanted)
  constexpr size_t kSkipped = ~size_t{0};
  auto layer = [&](int id) {
    auto it = layer_of.find(id);
    if (it != layer_of.end()) return it->second;
    const auto n = named.find(id);
    const std::string name = n != named.end() ? n->second : id < 0 ? stem : stem + "_" + std::to_string(id);
    const bool wanted = o.layers.empty() || std::find(o.layers.begin(), o.layers.end(), name) != o.layers.end();
    slab->seen.push_back(name);
    return layer_of[id] = wanted ? slab->Layer(name) : kSkipped;
  };
  if (!reader->info().schema.layers) {
    layer(-1);  // an empty file still names its layer
  } else {
    for (const auto& [id, unused] : named) layer(id);  // named layers are listed even when the slab misses them
  }
  std::vector<ClipRegion> regions;
  for (const ClipRegion& r : s.regions()) regions.push_back(r.And(clip));
  ConsoleProgress progress("section: " + path);
  PointCloud chunk;
  while (reader->Read(1 << 20, &chunk) > 0) {
    for (size_t i = 0; i < chunk.size(); ++i) {
      const Eigen::Vector3d world = chunk.WorldPosition(i);
      if (!world.allFinite()) continue;
      for (size_t r = 0; r < regions.size(); ++r) {
        if (!regions[r].Contains(world)) continue;
        const size_t k = layer(chunk.layers.empty() ? -1 : chunk.layers[i]);
        if (k == kSkipped) break;
        const Rgb8 colour = chunk.colors.empty() ? Rgb8{200, 200, 200} : chunk.colors[i];
        slab->Add(k, s, world, SegmentOf(s, world, r), colour);
        break;
      }
    }
    slab->points_read += chunk.size();
    uint64_t held = 0;
    for (const auto& d : slab->drawing) held += d.size();
    if (o.max_points > 0 && held > o.max_points) {
      throw std::length_error("the slab holds more than " + std::to_string(o.max_points) + " points (the limit)");
    }
    if (o.checkpoint) o.checkpoint();
    progress.Update(reader->points_read(),
                    reader->info().count == io::kUnknownCount ? 0 : reader->info().count);
  }
  progress.Finish();
}

// A layer whose slab points fill an area (it lies in the section plane) rather than a line: most
// occupied cells of a grid at the lines' spacing have all eight neighbours occupied.
bool FillsAnArea(const std::vector<Eigen::Vector2d>& points, double cell) {
  if (points.size() < 50 || !(cell > 0)) return false;
  std::unordered_map<uint64_t, int> occupied;
  auto key = [](int64_t i, int64_t j) {
    return static_cast<uint64_t>(i + (1 << 30)) << 32 | static_cast<uint64_t>(j + (1 << 30));
  };
  for (const Eigen::Vector2d& p : points) {
    occupied[key(static_cast<int64_t>(std::floor(p.x() / cell)), static_cast<int64_t>(std::floor(p.y() / cell)))] = 1;
  }
  if (occupied.size() < 25) return false;
  size_t interior = 0;
  for (const auto& [k, unused] : occupied) {
    const int64_t i = static_cast<int64_t>(k >> 32) - (1 << 30), j = static_cast<int64_t>(k & 0xffffffff) - (1 << 30);
    bool all = true;
    for (int di = -1; di <= 1 && all; ++di) {
      for (int dj = -1; dj <= 1 && all; ++dj) all = occupied.count(key(i + di, j + dj)) > 0;
    }
    interior += all ? 1 : 0;
  }
  return interior > 0.3 * occupied.size();
}

// Section lines of every layer (drawing coordinates; extracted around a local origin so that
// survey coordinates keep their digits).
std::vector<SectionLayerResult> ExtractLines(const SectionOptions& o, const Slab& slab, const Eigen::Vector2d& origin) {
  std::vector<SectionLayerResult> out;
  section::SectionLineOptions lo;
  lo.spacing = o.spacing;
  lo.max_gap = o.max_gap;
  lo.Check();
  for (size_t k = 0; k < slab.names.size(); ++k) {
    if (o.checkpoint) o.checkpoint();
    SectionLayerResult r;
    r.name = slab.names[k];
    r.colour = sampling::DefaultLayerColour(r.name, k).rgb;
    r.points = slab.drawing[k].size();
    std::vector<Eigen::Vector2d> local;
    local.reserve(r.points);
    for (const Eigen::Vector2d& p : slab.drawing[k]) local.push_back(p - origin);
    section::SectionLines lines = section::ExtractSectionLines(lo, local);
    r.area = FillsAnArea(local, 1.5 * lines.spacing);
    if (!r.area) section::RefineSectionCorners(section::SectionCornerOptions{}, local, lines.spacing, &lines.lines);
    if (r.area) {
      LogWarning("layer " + r.name + ": its " + std::to_string(r.points) +
                 " slab points fill an area (the layer lies in the section plane): no section lines");
    } else {
      for (Polyline2 line : lines.lines) {
        for (Eigen::Vector2d& p : line.points) p += origin;
        for (size_t i = 1; i < line.points.size(); ++i) r.length += (line.points[i] - line.points[i - 1]).norm();
        if (line.closed) r.length += (line.points.front() - line.points.back()).norm();
        r.lines.push_back(std::move(line));
      }
    }
    out.push_back(std::move(r));
  }
  return out;
}

SectionWindow MakeWindow(const SectionOptions& o, const Slab& slab, double thickness) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& layer : slab.drawing) {
    for (const Eigen::Vector2d& p : layer) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  if (!(lo.x() <= hi.x())) lo = hi = Eigen::Vector2d::Zero();  // no points
  Eigen::Vector2d extent = (hi - lo).cwiseMax(Eigen::Vector2d::Constant(std::max(thickness, 1e-3)));
  const double margin = 0.05 * extent.maxCoeff();
  lo -= Eigen::Vector2d(margin, 3 * margin);  // room for the scale bar below
  extent += Eigen::Vector2d(2 * margin, 4 * margin);
  SectionWindow w;
  w.x0 = lo.x();
  w.y0 = lo.y();
  w.metres_per_pixel = o.pixel > 0 ? o.pixel : extent.x() / o.width;
  w.metres_per_pixel = std::max(w.metres_per_pixel, extent.maxCoeff() / 8192);  // at most 8192 pixels a side
  w.width = std::max(16, static_cast<int>(std::ceil(extent.x() / w.metres_per_pixel)));
  w.height = std::max(16, static_cast<int>(std::ceil(extent.y() / w.metres_per_pixel)));
  return w;
}

// The slab's points seen along the plane's normal: orthographic SPBR of (x, depth, y) with the
// drawing's x to the right and y up.
Image8 RenderSlab(const SectionOptions& o, const Slab& slab, const std::vector<SectionLayerResult>& layers,
                  const SectionWindow& w, double thickness) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  cloud.SetSchema(schema);
  for (size_t k = 0; k < slab.names.size(); ++k) {
    for (size_t i = 0; i < slab.drawing[k].size(); ++i) {
      const Eigen::Vector2d& p = slab.drawing[k][i];
      cloud.positions.push_back({p.x() - w.x0, slab.depth[k][i], p.y() - w.y0});
      cloud.colors.push_back(o.colours == SectionColours::kData ? slab.colours[k][i] : layers[k].colour);
    }
  }
  // A slab is thin and sparse: one copy per point (SPBR's 1/L weight) would leave it faint. Each
  // point goes to round(opacity L) of the L ensembles (opacity control's multiplicity), so a pixel
  // one point covers has that opacity, and where layers overlap the nearest of each ensemble
  // wins: see-through, as SPBR blends.
  const int copies = std::max(1, static_cast<int>(std::lround(o.opacity * o.spbr.repeat_level)));
  const int field = cloud.AddScalarField(render::kMultiplicityField);
  for (size_t i = 0; i < cloud.size(); ++i) cloud.scalars[field].Set(i, copies);
  render::Camera camera;
  camera.projection = render::Projection::kOrthographic;
  camera.width = w.width;
  camera.height = w.height;
  camera.ortho_height = w.height * w.metres_per_pixel;
  const double cx = 0.5 * w.width * w.metres_per_pixel, cz = 0.5 * camera.ortho_height;
  camera.target = {cx, 0, cz};
  camera.eye = {cx, -(thickness + 1), cz};
  camera.up = Eigen::Vector3d::UnitZ();
  render::SpbrResult result;
  if (cloud.empty()) {
    result.sums = render::Accumulator(w.width, w.height);
    result.repeat_level = result.ensembles = o.spbr.repeat_level;
  } else {
    render::SplatCloudOptions build;
    build.spbr = o.spbr;
    const render::SplatCloud splats = render::BuildSplatCloud(build, {&cloud});
    render::SpbrOptions spbr;
    spbr.threads = o.threads;
    camera.eye -= splats.frame.origin;
    camera.target -= splats.frame.origin;
    result = render::RenderSpbr(spbr, camera, splats);
  }
  return render::ToImage8(render::AverageImage(result, o.background, 1.0));
}

std::string SummaryJson(const SectionOptions& o, const std::vector<std::string>& inputs, const SectionPath& s,
                        const Slab& slab, const std::vector<SectionLayerResult>& layers, const SectionWindow& w,
                        double bar) {
  auto num = [](double v) { return FormatDouble(v); };
  std::string out = "{\n  \"candi\": \"" + std::string(kVersion) + "\",\n  \"section\": " + s.ToJson() + ",\n";
  out += "  \"inputs\": [";
  for (size_t i = 0; i < inputs.size(); ++i) out += (i ? ", " : "") + nlohmann::json(inputs[i]).dump();
  out += "],\n  \"points_read\": " + std::to_string(slab.points_read);
  if (slab.archive) {
    out += ",\n  \"chunks\": " + std::to_string(slab.chunks) + ",\n  \"chunks_read\": " + std::to_string(slab.chunks_read);
  }
  uint64_t total = 0;
  for (const auto& l : layers) total += l.points;
  out += ",\n  \"points\": " + std::to_string(total);
  out += ",\n  \"seconds\": {\"read\": " + num(slab.read_s) + ", \"lines\": " + num(slab.lines_s) +
         ", \"image\": " + num(slab.image_s) + "}";
  if (total == 0) out += ",\n  \"message\": \"no points within the slab\"";
  out += ",\n  \"image\": {\"file\": \"section.png\", \"x0\": " + num(w.x0) +
         ", \"y0\": " + num(w.y0) + ", \"metres_per_pixel\": " + num(w.metres_per_pixel) +
         ", \"width\": " + std::to_string(w.width) + ", \"height\": " + std::to_string(w.height) +
         ", \"scale_bar_m\": " + num(bar) +
         ", \"repeat_level\": " + std::to_string(o.spbr.repeat_level) +
         ", \"opacity\": " + num(o.opacity) + ", \"seed\": " + std::to_string(o.spbr.seed) +
         "},\n  \"layers\": [";
  for (size_t k = 0; k < layers.size(); ++k) {
    const SectionLayerResult& l = layers[k];
    out += std::string(k ? "," : "") + "\n    {\"name\": " + nlohmann::json(l.name).dump() + ", \"points\": " +
           std::to_string(l.points) + ", \"lines\": " + std::to_string(l.lines.size()) + ", \"length_m\": " +
           num(l.length) + ", \"in_plane\": " + (l.area ? "true" : "false") + "}";
  }
  return out + "\n  ]\n}\n";
}

// The DXF drawing: one DXF layer per section layer, in its colour.
std::vector<section::DxfLayerLines> DxfLayers(const SectionCut& cut) {
  std::vector<section::DxfLayerLines> dxf;
  for (const SectionLayerResult& l : cut.layers) {
    dxf.push_back({l.name, uint32_t{l.colour.r} << 16 | uint32_t{l.colour.g} << 8 | l.colour.b, l.lines});
  }
  return dxf;
}

section::DxfWriteOptions DxfOptions(const SectionCut& cut) {
  section::DxfWriteOptions o;
  o.comment = "candi section: " + cut.describe;
  return o;
}

}  // namespace

void SectionOptions::Check() const {
  CANDI_CHECK_OPTION(spacing >= 0 && std::isfinite(spacing), spacing, "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(max_gap >= 0 && std::isfinite(max_gap), max_gap, "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION_IN(width, 16, 8192);
  CANDI_CHECK_OPTION(pixel >= 0 && std::isfinite(pixel), pixel, ">= 0 m");
  CANDI_CHECK_OPTION_IN(spbr.repeat_level, 1, 10000);  // narrower than SpbrSettings' range: first
  spbr.Check();
  CANDI_CHECK_OPTION(!spbr.opaque, spbr.opaque, "false (a section blends its slab)");
  CANDI_CHECK_OPTION(opacity > 0 && opacity <= 1, opacity, "in (0, 1]");
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

uint64_t SectionCut::Points() const {
  uint64_t total = 0;
  for (const auto& l : layers) total += l.points;
  return total;
}

SectionCut CutSection(const SectionOptions& o, const std::vector<std::string>& inputs, const SectionPath& section,
                      const ClipRegion& clip) {
  o.Check();
  Slab slab;
  Stopwatch lap;
  for (const std::string& in : inputs) {
    // An archive, a build directory (its archive/), or a demo's output (its build in archive/).
    const std::string dir = render::FindArchive(in);
    if (!dir.empty() && inputs.size() > 1) throw std::invalid_argument(in + " is an archive: section it alone");
    if (!dir.empty()) ReadArchiveSlab(o, dir, section, clip, &slab);
    else ReadFileSlab(o, in, section, clip, &slab);
  }
  for (const std::string& name : o.layers) {
    if (!slab.archive && std::find(slab.seen.begin(), slab.seen.end(), name) == slab.seen.end()) {
      std::string known;
      for (const std::string& n : slab.seen) known += (known.empty() ? "" : ", ") + n;
      throw std::invalid_argument("--layers: no layer '" + name + "' in the input (it has " + known + ")");
    }
  }
  slab.read_s = lap.Lap();
  SectionCut cut;
  cut.inputs = inputs;
  cut.describe = section.Describe();
  cut.window = MakeWindow(o, slab, section.thickness());
  cut.layers = ExtractLines(o, slab, Eigen::Vector2d(std::round(cut.window.x0), std::round(cut.window.y0)));
  slab.lines_s = lap.Lap();
  if (cut.Points() == 0) LogWarning("section: no points within the slab (" + cut.describe + ")");
  if (o.checkpoint) o.checkpoint();
  cut.image = RenderSlab(o, slab, cut.layers, cut.window, section.thickness());
  slab.image_s = lap.Lap();
  cut.scale_bar_m = section::DrawScaleBar(cut.window, o.background, &cut.image);
  cut.image_text = {{"Software", std::string("candi ") + kVersion},
                    {"candi:section", cut.describe},
                    {"candi:window", "x0 " + FormatDouble(cut.window.x0) + " y0 " + FormatDouble(cut.window.y0) +
                                         " metres_per_pixel " + FormatDouble(cut.window.metres_per_pixel)},
                    {"candi:points", cut.Points() == 0 ? "none: no points within the slab" : std::to_string(cut.Points())}};
  cut.summary = SummaryJson(o, inputs, section, slab, cut.layers, cut.window, cut.scale_bar_m);
  cut.archive = slab.archive;
  cut.chunks = slab.chunks;
  cut.chunks_read = slab.chunks_read;
  cut.points_read = slab.points_read;
  return cut;
}

void WriteSection(const SectionCut& cut, const SectionPath& section, const std::string& dir) {
  fs::create_directories(dir);  // errors name the path
  const fs::path out(dir);
  io::WritePng((out / "section.png").string(), cut.image, cut.image_text);
  section::WriteSectionDxf(DxfOptions(cut), DxfLayers(cut), (out / "section.dxf").string());
  WriteFileAtomic((out / "section.csv").string(), section::SectionCsv(cut.layers, section));
  WriteFileAtomic((out / "section.svg").string(),
                  section::SectionSvg(cut.layers, cut.window, "section.png", cut.describe, cut.scale_bar_m));
  WriteFileAtomic((out / "section.json").string(), cut.summary);
}

std::string ExportViewerSection(const std::string& archive_dir, const render::ArchiveManifest& m,
                                const SectionOptions& base, uint64_t seq, const view::SectionRequest& r,
                                const view::ViewState& state) {
  SectionOptions o = base;
  o.layers.clear();
  const std::vector<double>& f = state.settings.layer_fraction;
  for (size_t k = 0; k < f.size() && k < m.layers.size(); ++k) {
    if (f[k] > 0) o.layers.push_back(m.layers[k].name);
  }
  if (!f.empty() && o.layers.empty()) throw std::invalid_argument("every layer is hidden");
  if (o.layers.size() == m.layers.size()) o.layers.clear();
  const SectionPath path = SectionPath::Plane(r.point, r.normal, r.thickness);
  const SectionCut cut = CutSection(o, {archive_dir}, path, state.settings.clip);
  if (o.checkpoint) o.checkpoint();
  return nlohmann::json{{"type", "section"},
                        {"seq", seq},
                        {"summary", nlohmann::json::parse(cut.summary)},
                        {"dxf", section::SectionDxfText(DxfOptions(cut), DxfLayers(cut))},
                        {"svg", section::SectionSvg(cut.layers, cut.window, "section.png", cut.describe,
                                                    cut.scale_bar_m)},
                        {"csv", section::SectionCsv(cut.layers, path)},
                        {"png_base64", Base64(io::EncodePng(cut.image, cut.image_text))}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace candi::pipeline
