// candi section IN... --plane|--through|--path ... --thickness T -o OUT: the points of a slab, per
// layer, as an orthographic SPBR image (see-through, a scale bar) and as section lines (DXF with
// one layer per archive layer, CSV, SVG), with a JSON summary. An archive (or a build directory's)
// is read only where the slab crosses its chunks; point files are streamed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/version.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "render/archive.h"
#include "render/archive_clip.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"
#include "sampling/layer_colours.h"
#include "section/section_corners.h"
#include "section/section_dxf.h"
#include "section/section_lines.h"
#include "section/section_outputs.h"
#include "section/section_path.h"

namespace candi::app {

namespace {

namespace fs = std::filesystem;

// The slab's points, per layer, in drawing coordinates.
struct Slab {
  std::vector<std::string> names;
  std::vector<std::vector<Eigen::Vector2d>> drawing;  // per layer
  std::vector<std::vector<float>> depth;              // per layer: signed distance from the plane
  std::vector<std::vector<Rgb8>> colours;             // per layer: the points' own colours
  uint64_t chunks = 0, chunks_read = 0, points_read = 0;
  bool archive = false;
  double read_s = 0, lines_s = 0, image_s = 0;  // stage timings
  std::vector<std::string> seen;                      // every layer name of the inputs (--layers)

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
  void Add(size_t layer, const section::SectionPath& s, const Eigen::Vector3d& world, size_t segment, Rgb8 colour) {
    double d = 0;
    drawing[layer].push_back(s.ToDrawing(world, segment, &d));
    depth[layer].push_back(static_cast<float>(d));
    colours[layer].push_back(colour);
  }
};

section::SectionPath ParseSection(const SectionArgs& a) {
  const int given = !a.plane.empty() + !a.through.empty() + !a.path.empty();
  if (given != 1) throw std::invalid_argument("give one of --plane, --through and --path");
  if (!a.plane.empty()) {
    const std::vector<double> v = ParseNumbers(a.plane, ',', "--plane");
    if (v.size() != 6) throw std::invalid_argument("--plane '" + a.plane + "': expected px,py,pz,nx,ny,nz");
    return section::SectionPath::Plane({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  if (!a.through.empty()) {
    const std::vector<double> v = ParseNumbers(a.through, ',', "--through");
    if (v.size() == 4) return section::SectionPath::Through({v[0], v[1], 0}, {v[2], v[3], 0}, a.thickness);
    if (v.size() != 6) throw std::invalid_argument("--through '" + a.through + "': expected x1,y1,x2,y2 or x1,y1,z1,x2,y2,z2");
    return section::SectionPath::Through({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  const std::vector<double> v = ParseNumbers(a.path, ',', "--path");
  if (v.size() % 2 != 0) throw std::invalid_argument("--path '" + a.path + "': expected x1,y1,x2,y2,... (plan vertices)");
  std::vector<Eigen::Vector2d> plan;
  for (size_t i = 0; i + 1 < v.size(); i += 2) plan.push_back({v[i], v[i + 1]});
  size_t merged = 0;
  section::SectionPath s = section::SectionPath::Path(plan, a.thickness, &merged);
  if (merged > 0) LogWarning("--path: " + std::to_string(merged) + " repeated vertices merged");
  return s;
}

// The segment a slab point belongs to: 0 for a plane; for a path the segment nearest in plan when
// its slab holds the point, else the first slab that does (`first_region`).
size_t SegmentOf(const section::SectionPath& s, const Eigen::Vector3d& world, size_t first_region) {
  if (!s.is_path()) return 0;
  const size_t nearest = s.NearestSegment(world);
  return s.regions()[nearest].Contains(world) ? nearest : first_region;
}

void ReadArchiveSlab(const SectionArgs& a, const std::string& dir, const section::SectionPath& s, const ClipRegion& clip,
                     Slab* slab) {
  const render::Archive archive(dir);
  const render::ArchiveManifest& m = archive.manifest();
  render::ClippedReadOptions o;
  o.threads = a.threads;
  if (!a.layers.empty()) {
    o.layers.assign(m.layers.size(), 0);
    for (const std::string& name : a.layers) {
      bool found = false;
      for (size_t k = 0; k < m.layers.size(); ++k) {
        if (m.layers[k].name == name) o.layers[k] = found = true;
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
    if (o.layers.empty() || o.layers[k]) slab->Layer(m.layers[k].name);
  }
  ConsoleProgress progress("section: reading the chunks the slab crosses");
  const render::ClippedPoints got = render::ReadClipped(o, archive, regions, progress.Callback());
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

// "candi_layers 0=A 1=B" (sampling/layer_clouds.h) as id -> name.
std::map<int, std::string> LayerNamesOf(const PointCloudMeta& meta) {
  std::map<int, std::string> names;
  for (const std::string& c : meta.comments) {
    if (c.rfind("candi_layers", 0) != 0) continue;
    size_t p = 12;
    while (p < c.size()) {
      const size_t end = std::min(c.find(' ', p + 1), c.size());
      const std::string item = c.substr(p, end - p);
      const size_t eq = item.find('=');
      if (eq != std::string::npos) {
        try {
          names[std::stoi(item.substr(0, eq))] = item.substr(eq + 1);
        } catch (const std::exception&) {
        }
      }
      p = end;
    }
  }
  return names;
}

void ReadFileSlab(const SectionArgs& a, const std::string& path, const section::SectionPath& s, const ClipRegion& clip,
                  Slab* slab) {
  io::PointReadOptions read;
  read.columns = a.columns;
  read.scalar_fields = false;
  auto reader = io::OpenPointReader(path, read);
  const std::string stem = fs::path(path).stem().string();
  const std::map<int, std::string> named = LayerNamesOf(reader->info().meta);
  std::unordered_map<int, size_t> layer_of;  // the file's layer id -> slab layer (kSkipped: not wanted)
  constexpr size_t kSkipped = ~size_t{0};
  auto layer = [&](int id) {
    auto it = layer_of.find(id);
    if (it != layer_of.end()) return it->second;
    const auto n = named.find(id);
    const std::string name = n != named.end() ? n->second : id < 0 ? stem : stem + "_" + std::to_string(id);
    const bool wanted = a.layers.empty() || std::find(a.layers.begin(), a.layers.end(), name) != a.layers.end();
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
    progress.Update(reader->points_read(), reader->info().count == io::kUnknownCount ? 0 : reader->info().count);
  }
  progress.Finish();
}

// A layer whose slab points fill an area (it lies in the section plane) rather than a line: most
// occupied cells of a grid at the lines' spacing have all eight neighbours occupied.
bool FillsAnArea(const std::vector<Eigen::Vector2d>& points, double cell) {
  if (points.size() < 50 || !(cell > 0)) return false;
  std::unordered_map<uint64_t, int> occupied;
  auto key = [](int64_t i, int64_t j) { return static_cast<uint64_t>(i + (1 << 30)) << 32 | static_cast<uint64_t>(j + (1 << 30)); };
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
std::vector<section::SectionLayerResult> ExtractLines(const SectionArgs& a, const Slab& slab, const Eigen::Vector2d& origin) {
  std::vector<section::SectionLayerResult> out;
  section::SectionLineOptions o;
  o.spacing = a.spacing;
  o.max_gap = a.max_gap;
  o.Check();
  for (size_t k = 0; k < slab.names.size(); ++k) {
    section::SectionLayerResult r;
    r.name = slab.names[k];
    r.colour = sampling::DefaultLayerColour(r.name, k).rgb;
    r.points = slab.drawing[k].size();
    std::vector<Eigen::Vector2d> local;
    local.reserve(r.points);
    for (const Eigen::Vector2d& p : slab.drawing[k]) local.push_back(p - origin);
    section::SectionLines lines = section::ExtractSectionLines(o, local);
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

section::SectionWindow MakeWindow(const SectionArgs& a, const Slab& slab) {
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& layer : slab.drawing) {
    for (const Eigen::Vector2d& p : layer) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  if (!(lo.x() <= hi.x())) lo = hi = Eigen::Vector2d::Zero();  // no points
  Eigen::Vector2d extent = (hi - lo).cwiseMax(Eigen::Vector2d::Constant(std::max(a.thickness, 1e-3)));
  const double margin = 0.05 * extent.maxCoeff();
  lo -= Eigen::Vector2d(margin, 3 * margin);  // room for the scale bar below
  extent += Eigen::Vector2d(2 * margin, 4 * margin);
  section::SectionWindow w;
  w.x0 = lo.x();
  w.y0 = lo.y();
  w.metres_per_pixel = a.pixel > 0 ? a.pixel : extent.x() / a.width;
  w.metres_per_pixel = std::max(w.metres_per_pixel, extent.maxCoeff() / 8192);  // at most 8192 pixels a side
  w.width = std::max(16, static_cast<int>(std::ceil(extent.x() / w.metres_per_pixel)));
  w.height = std::max(16, static_cast<int>(std::ceil(extent.y() / w.metres_per_pixel)));
  return w;
}

Rgb8 ParseBackground(const std::string& text) {
  const std::vector<double> v = ParseNumbers(text, ',', "--background");
  if (v.size() != 3) throw std::invalid_argument("--background '" + text + "': expected r,g,b");
  for (double c : v) {
    if (c < 0 || c > 255 || c != std::floor(c)) throw std::invalid_argument("--background '" + text + "': 0..255 each");
  }
  return {static_cast<uint8_t>(v[0]), static_cast<uint8_t>(v[1]), static_cast<uint8_t>(v[2])};
}

// The slab's points seen along the plane's normal: orthographic SPBR of (x, depth, y) with the
// drawing's x to the right and y up.
Image8 RenderSlab(const SectionArgs& a, const Slab& slab, const std::vector<section::SectionLayerResult>& layers,
                  const section::SectionWindow& w, Rgb8 background) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  cloud.SetSchema(schema);
  for (size_t k = 0; k < slab.names.size(); ++k) {
    for (size_t i = 0; i < slab.drawing[k].size(); ++i) {
      const Eigen::Vector2d& p = slab.drawing[k][i];
      cloud.positions.push_back({p.x() - w.x0, slab.depth[k][i], p.y() - w.y0});
      cloud.colors.push_back(a.colours == "data" ? slab.colours[k][i] : layers[k].colour);
    }
  }
  // A slab is thin and sparse: one copy per point (SPBR's 1/L weight) would leave it faint. Each
  // point goes to round(opacity L) of the L ensembles (opacity control's multiplicity), so a pixel
  // one point covers has that opacity, and where layers overlap the nearest of each ensemble
  // wins: see-through, as SPBR blends.
  const int copies = std::max(1, static_cast<int>(std::lround(a.opacity * a.repeat_level)));
  const int field = cloud.AddScalarField(render::kMultiplicityField);
  for (size_t i = 0; i < cloud.size(); ++i) cloud.scalars[field].Set(i, copies);
  render::Camera camera;
  camera.projection = render::Projection::kOrthographic;
  camera.width = w.width;
  camera.height = w.height;
  camera.ortho_height = w.height * w.metres_per_pixel;
  const double cx = 0.5 * w.width * w.metres_per_pixel, cz = 0.5 * camera.ortho_height;
  camera.target = {cx, 0, cz};
  camera.eye = {cx, -(a.thickness + 1), cz};
  camera.up = Eigen::Vector3d::UnitZ();
  render::SpbrResult result;
  if (cloud.empty()) {
    result.sums = render::Accumulator(w.width, w.height);
    result.repeat_level = result.ensembles = a.repeat_level;
  } else {
    render::SplatCloudOptions build;
    build.repeat_level = a.repeat_level;
    build.seed = a.seed;
    const render::SplatCloud splats = render::BuildSplatCloud(build, {&cloud});
    render::SpbrOptions o;
    o.threads = a.threads;
    o.point_size = a.point_size;
    camera.eye -= splats.frame.origin;
    camera.target -= splats.frame.origin;
    result = render::RenderSpbr(o, camera, splats);
  }
  return render::ToImage8(render::AverageImage(result, background, 1.0));
}

std::string SummaryJson(const SectionArgs& a, const section::SectionPath& s, const Slab& slab,
                        const std::vector<section::SectionLayerResult>& layers, const section::SectionWindow& w, double bar) {
  auto num = [](double v) { return FormatDouble(v); };
  std::string out = "{\n  \"candi\": \"" + std::string(kVersion) + "\",\n  \"section\": " + s.ToJson() + ",\n";
  out += "  \"inputs\": [";
  for (size_t i = 0; i < a.inputs.size(); ++i) out += (i ? ", " : "") + nlohmann::json(a.inputs[i]).dump();
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
  out += ",\n  \"image\": {\"file\": \"section.png\", \"x0\": " + num(w.x0) + ", \"y0\": " + num(w.y0) +
         ", \"metres_per_pixel\": " + num(w.metres_per_pixel) + ", \"width\": " + std::to_string(w.width) +
         ", \"height\": " + std::to_string(w.height) + ", \"scale_bar_m\": " + num(bar) + ", \"repeat_level\": " +
         std::to_string(a.repeat_level) + ", \"opacity\": " + num(a.opacity) + ", \"seed\": " + std::to_string(a.seed) + "},\n  \"layers\": [";
  for (size_t k = 0; k < layers.size(); ++k) {
    const section::SectionLayerResult& l = layers[k];
    out += std::string(k ? "," : "") + "\n    {\"name\": " + nlohmann::json(l.name).dump() + ", \"points\": " +
           std::to_string(l.points) + ", \"lines\": " + std::to_string(l.lines.size()) + ", \"length_m\": " +
           num(l.length) + ", \"in_plane\": " + (l.area ? "true" : "false") + "}";
  }
  return out + "\n  ]\n}\n";
}

}  // namespace

std::string RunSectionInto(const SectionArgs& a, const section::SectionPath& section, const ClipRegion& clip, bool print) {
  if (a.colours != "layer" && a.colours != "data") throw std::invalid_argument("--colours '" + a.colours + "': expected layer or data");
  if (a.repeat_level < 1 || a.repeat_level > 10000) throw std::invalid_argument("--repeat-level: must be in [1, 10000]");
  if (!(a.width >= 16 && a.width <= 8192)) throw std::invalid_argument("--width: must be in [16, 8192] pixels");
  if (!(a.pixel >= 0) || !std::isfinite(a.pixel)) throw std::invalid_argument("--pixel: must be >= 0 m");
  if (!(a.opacity > 0 && a.opacity <= 1)) throw std::invalid_argument("--opacity: must be in (0, 1]");
  if (!(a.point_size >= 1 && a.point_size <= 64)) throw std::invalid_argument("--point-size: must be in [1, 64] pixels");
  const Rgb8 background = ParseBackground(a.background);
  Slab slab;
  auto start = std::chrono::steady_clock::now();
  auto lap = [&start] {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - start).count();
    start = now;
    return s;
  };
  for (const std::string& in : a.inputs) {
    // An archive, a build directory (its archive/), or a demo's output (its build in archive/).
    std::string dir;
    for (const fs::path& p : {fs::path(in), fs::path(in) / "archive", fs::path(in) / "archive" / "archive"}) {
      if (dir.empty() && render::IsArchive(p.string())) dir = p.string();
    }
    if (!dir.empty() && a.inputs.size() > 1) throw std::invalid_argument(in + " is an archive: section it alone");
    if (!dir.empty()) ReadArchiveSlab(a, dir, section, clip, &slab);
    else ReadFileSlab(a, in, section, clip, &slab);
  }
  for (const std::string& name : a.layers) {
    if (!slab.archive && std::find(slab.seen.begin(), slab.seen.end(), name) == slab.seen.end()) {
      std::string known;
      for (const std::string& n : slab.seen) known += (known.empty() ? "" : ", ") + n;
      throw std::invalid_argument("--layers: no layer '" + name + "' in the input (it has " + known + ")");
    }
  }
  slab.read_s = lap();
  const section::SectionWindow window = MakeWindow(a, slab);
  const std::vector<section::SectionLayerResult> layers =
      ExtractLines(a, slab, Eigen::Vector2d(std::round(window.x0), std::round(window.y0)));
  slab.lines_s = lap();
  uint64_t total = 0;
  for (const auto& l : layers) total += l.points;
  if (total == 0) LogWarning("section: no points within the slab (" + section.Describe() + ")");

  fs::create_directories(a.output);  // errors name the path
  Image8 image = RenderSlab(a, slab, layers, window, background);
  slab.image_s = lap();
  const double bar = section::DrawScaleBar(window, background, &image);
  const io::PngText text = {{"Software", std::string("candi ") + kVersion},
                        {"candi:section", section.Describe()},
                        {"candi:window", "x0 " + FormatDouble(window.x0) + " y0 " + FormatDouble(window.y0) +
                                             " metres_per_pixel " + FormatDouble(window.metres_per_pixel)},
                        {"candi:points", total == 0 ? "none: no points within the slab" : std::to_string(total)}};
  const fs::path out(a.output);
  io::WritePng((out / "section.png").string(), image, text);
  std::vector<section::DxfLayerLines> dxf;
  for (const section::SectionLayerResult& l : layers) {
    dxf.push_back({l.name, uint32_t{l.colour.r} << 16 | uint32_t{l.colour.g} << 8 | l.colour.b, l.lines});
  }
  section::DxfWriteOptions dxf_options;
  dxf_options.comment = "candi section: " + section.Describe();
  section::WriteSectionDxf(dxf_options, dxf, (out / "section.dxf").string());
  section::WriteSectionCsv((out / "section.csv").string(), layers, section);
  section::WriteSectionSvg((out / "section.svg").string(), layers, window, "section.png", section.Describe(), bar);
  const std::string summary = SummaryJson(a, section, slab, layers, window, bar);
  section::WriteTextFile((out / "section.json").string(), summary);
  if (!print) return summary;

  std::printf("%s: %s\n", a.output.c_str(), section.Describe().c_str());
  if (slab.archive) {
    std::printf("  read %llu of %llu chunks (%llu points)\n", static_cast<unsigned long long>(slab.chunks_read),
                static_cast<unsigned long long>(slab.chunks), static_cast<unsigned long long>(slab.points_read));
  }
  std::printf("  %-16s %10s %6s %10s\n", "layer", "points", "lines", "length m");
  for (const section::SectionLayerResult& l : layers) {
    std::printf("  %-16s %10llu %6zu %10.3f%s\n", l.name.c_str(), static_cast<unsigned long long>(l.points),
                l.lines.size(), l.length, l.area ? "  (lies in the plane: no lines)" : "");
  }
  return summary;
}

int RunSection(const SectionArgs& a) {
  RunSectionInto(a, ParseSection(a), ParseClip(a.clip.box, a.clip.planes), /*print=*/true);
  return kOk;
}

}  // namespace candi::app
