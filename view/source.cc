#include "view/source.h"

#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/mapped_file.h"
#include "core/parallel.h"
#include "io/point_io.h"
#include "io/point_records.h"
#include "render/archive_pack.h"
#include "render/view_json.h"

namespace candi::view {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json ReadJson(const std::string& path) {
  try {
    return json::parse(ReadFileToString(path));
  } catch (const json::exception& e) {
    throw InputError(path, "", std::string("not valid JSON: ") + e.what());
  }
}

// The scene's "render" block (repeat level, size, background, brightness), when the scene file
// a build names is still there; anything unreadable keeps the defaults (the viewer's settings
// are the page's to change).
void SceneSettings(const json& provenance, ViewerSource* source) {
  if (!provenance.contains("scene") || !provenance["scene"].is_object()) return;
  const json& scene = provenance["scene"];
  if (!scene.contains("path") || !scene["path"].is_string()) return;
  const std::string path = scene["path"].get<std::string>();
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return;
  json s;
  try {
    s = json::parse(ReadFileToString(path));
  } catch (const std::exception&) {
    return;
  }
  if (!s.is_object() || !s.contains("render") || !s["render"].is_object()) return;
  const json& r = s["render"];
  ViewSettings& v = source->settings;
  if (r.contains("repeat_level") && r["repeat_level"].is_number_integer()) {
    v.repeat_level = std::clamp(r["repeat_level"].get<int>(), 1, kMaxRepeatLevel);
  }
  if (r.contains("width") && r["width"].is_number_integer() && r.contains("height") && r["height"].is_number_integer()) {
    source->first_view.width = std::clamp(r["width"].get<int>(), 1, kMaxImageSide);
    source->first_view.height = std::clamp(r["height"].get<int>(), 1, kMaxImageSide);
  }
  if (r.contains("background") && r["background"].is_array() && r["background"].size() == 3) {
    const json& b = r["background"];
    if (b[0].is_number_integer() && b[1].is_number_integer() && b[2].is_number_integer()) {
      v.background = {static_cast<uint8_t>(std::clamp(b[0].get<int>(), 0, 255)),
                      static_cast<uint8_t>(std::clamp(b[1].get<int>(), 0, 255)),
                      static_cast<uint8_t>(std::clamp(b[2].get<int>(), 0, 255))};
    }
  }
  if (r.contains("brightness")) {
    if (r["brightness"] == "none") v.brightness = 1;
    else if (r["brightness"].is_number() && r["brightness"].get<double>() > 0) v.brightness = r["brightness"].get<double>();
  }
  if (s.contains("seed") && s["seed"].is_number_unsigned()) v.seed = s["seed"].get<uint64_t>();
}

// What a visitor needs to tell measured from reconstructed: per layer its kind, method and
// sources (file names and SHA-256, not the build machine's paths), the CRS, the scene's licence
// and annotations. Fields of the wrong type are left out (the page shows what there is).
json Provenance(const json& p) {
  json out = json::object();
  if (p.contains("crs") && p["crs"].is_object()) out["crs"] = p["crs"];
  if (p.contains("licence") && p["licence"].is_string()) out["licence"] = p["licence"];
  if (p.contains("annotations") && p["annotations"].is_array()) out["annotations"] = p["annotations"];
  json layers = json::array();
  if (p.contains("layers") && p["layers"].is_array()) {
    for (const json& l : p["layers"]) {
      if (!l.is_object()) continue;
      json e = json::object();
      for (const char* key : {"name", "kind", "method"}) {
        if (l.contains(key) && l[key].is_string()) e[key] = l[key];
      }
      if (l.contains("scanned") && l["scanned"].is_boolean()) e["scanned"] = l["scanned"];
      if (l.contains("crs") && l["crs"].is_object()) e["crs"] = l["crs"];
      json sources = json::array();
      if (l.contains("sources") && l["sources"].is_array()) {
        for (const json& src : l["sources"]) {
          if (!src.is_object() || !src.contains("path") || !src["path"].is_string()) continue;
          json s = {{"file", fs::path(src["path"].get<std::string>()).filename().string()}};
          if (src.contains("sha256") && src["sha256"].is_string()) s["sha256"] = src["sha256"];
          sources.push_back(s);
        }
      }
      e["sources"] = sources;
      layers.push_back(e);
    }
  }
  out["layers"] = layers;
  return out;
}

ViewerSource FromBuild(const fs::path& dir, const render::Orientation& orientation) {
  ViewerSource source;
  source.kind = "build";
  source.archive_dir = (dir / "archive").string();
  const std::string provenance_path = (dir / "archive.json").string();
  const json p = ReadJson(provenance_path);
  if (!p.is_object()) throw InputError(provenance_path, "/", "expected a JSON object");
  source.title = p.value("name", dir.filename().string());
  if (p.contains("layers") && p["layers"].is_array()) {
    for (const json& l : p["layers"]) {
      if (!l.is_object()) continue;
      SourceLayer layer;
      layer.name = l.value("name", "");
      layer.kind = l.value("kind", "");
      layer.points = l.value("points", uint64_t{0});
      layer.opacity = l.value("opacity", 1.0);
      layer.highlight = l.value("highlight", false);
      source.layers.push_back(layer);
    }
  }
  source.provenance_json = Provenance(p).dump();
  const render::Archive archive(source.archive_dir);
  const render::ArchiveManifest& m = archive.manifest();
  SceneSettings(p, &source);
  source.legend = m.colour_by;
  source.first_view = render::FirstView(m.bounds.Translated(m.frame.origin), source.first_view.width,
                                source.first_view.height, orientation);
  if (p.contains("views") && p["views"].is_array()) {
    for (const json& v : p["views"]) {
      if (!v.is_object() || !v.contains("name") || !v["name"].is_string()) continue;
      const std::string name = v["name"].get<std::string>();
      const fs::path file = dir / "renders" / (name + ".view.json");
      std::error_code ec;
      if (!fs::is_regular_file(file, ec)) continue;
      source.views.push_back({name, render::ParseView(ReadFileToString(file.string()), file.string()),
                              v.value("opaque", false)});
    }
  }
  return source;
}

}  // namespace

namespace {

std::string Hex(Rgb8 c) {
  char text[8];
  std::snprintf(text, sizeof(text), "#%02x%02x%02x", c.r, c.g, c.b);
  return text;
}

// The legend as the page draws it: the scale's colours at 11 evenly spaced values (or the classes
// with their colours and names), the range, and the grey's counts.
json LegendJson(const FieldLegend& l) {
  json j = {{"field", l.field}, {"scale", FieldScaleName(l.scale)}, {"lo", l.lo}, {"hi", l.hi},
            {"count", l.count}, {"outside", l.outside}, {"undefined", l.undefined},
            {"grey", Hex(kOutOfRangeGrey)}};
  if (l.scale == FieldScale::kClasses) {
    json classes = json::array();
    for (int c : l.classes) classes.push_back({{"code", c}, {"name", ClassName(c)}, {"colour", Hex(ClassColour(c))}});
    j["classes"] = classes;
  } else {
    json stops = json::array();
    for (int i = 0; i <= 10; ++i) stops.push_back(Hex(l.Colour(l.lo + (l.hi - l.lo) * i / 10.0)));
    j["stops"] = stops;
    // What a picked colour stands for, for a page without a server (candi publish): the scale's
    // colours along `steps` + 1 even values from lo to hi, as runs [0xRRGGBB, first, last].
    json runs = json::array();
    for (const FieldLegend::ColourRun& r : l.ColourRuns()) {
      runs.push_back({(r.colour.r << 16) | (r.colour.g << 8) | r.colour.b, r.first, r.last});
    }
    j["steps"] = FieldLegend::kColourSteps;
    j["runs"] = runs;
  }
  return j;
}

}  // namespace

std::string ViewerSource::ToJson(const render::ArchiveManifest& m) const {
  // The archive's layers (what the page can show and hide), with what the build says of each.
  json layers_json = json::array();
  for (const render::ArchiveLayer& a : m.layers) {
    json l = {{"name", a.name}, {"points", a.points}, {"kind", ""}, {"opacity", 1.0}, {"highlight", false}};
    for (const SourceLayer& s : layers) {
      if (s.name != a.name) continue;
      l["kind"] = s.kind;
      l["opacity"] = s.opacity;
      l["highlight"] = s.highlight;
    }
    layers_json.push_back(l);
  }
  json views_json = json::array();
  for (const SavedView& v : views) {
    views_json.push_back({{"name", v.name}, {"camera", json::parse(render::ViewToJson(v.camera))}, {"opaque", v.opaque}});
  }
  const Box3d world = m.bounds.Translated(m.frame.origin);
  json s = {{"title", title},
            {"kind", kind},
            {"points", m.points},
            {"chunks", m.chunks.size()},
            {"origin", Vec(m.frame.origin)},
            {"bounds", {{"min", Vec(world.min)}, {"max", Vec(world.max)}}},
            {"layers", layers_json},
            {"views", views_json},
            {"first_view", json::parse(render::ViewToJson(first_view))},
            {"settings",
             {{"repeat_level", settings.repeat_level},
              {"point_size", settings.point_size},
              {"background", {settings.background.r, settings.background.g, settings.background.b}},
              {"brightness", settings.brightness < 0 ? json("auto") : json(settings.brightness)},
              {"opaque", settings.opaque},
              {"seed", settings.seed},
              {"clip", ClipPlaneArrays(settings.clip)}}}};
  if (!provenance_json.empty()) s["provenance"] = json::parse(provenance_json);
  if (legend) s["legend"] = LegendJson(*legend);
  if (preview_every > 0) s["preview"] = {{"every", preview_every}, {"points", preview_points}};
  return s.dump(-1, ' ', false, json::error_handler_t::replace);
}

ViewerSource OpenViewerSource(const std::string& path, const render::Orientation& orientation) {
  std::error_code ec;
  const fs::path p(path);
  // A build directory, or a demo's output holding one in archive/ (what candi section opens).
  for (const fs::path& build : {p, p / "archive"}) {
    if (fs::is_regular_file(build / "archive.json", ec) && render::IsArchive((build / "archive").string())) {
      return FromBuild(build, orientation);
    }
  }
  if (!render::IsArchive(path)) {
    throw InputError(path, "", "neither a build directory (archive.json and archive/), a demo's output holding one in "
                               "archive/, nor a render archive (manifest.json)");
  }
  ViewerSource source;
  source.kind = "archive";
  source.archive_dir = path;
  source.title = fs::absolute(p).lexically_normal().filename().string();
  if (source.title.empty()) source.title = fs::absolute(p).lexically_normal().parent_path().filename().string();
  const render::Archive archive(path);
  const render::ArchiveManifest& m = archive.manifest();
  source.first_view = render::FirstView(m.bounds.Translated(m.frame.origin), 1024, 768, orientation);
  source.legend = m.colour_by;
  return source;
}

namespace {

// A fresh temporary directory for an archive (its path + "/archive"), removed again when `pack`
// throws.
ViewerSource PackIntoTemporary(const std::vector<std::string>& files, const render::Orientation& orientation,
                               const std::function<void(const std::string& archive_dir)>& pack) {
  std::string tmpl = (fs::temp_directory_path() / "candi-view-XXXXXX").string();
  const int id = MakeTempDirectory(&tmpl);  // an interrupt while packing removes it
  if (id < 0) throw InputError(tmpl, "", std::string("cannot create a temporary directory: ") + std::strerror(errno));
  const std::string archive_dir = tmpl + "/archive";
  ViewerSource source;
  try {
    pack(archive_dir);
    source = OpenViewerSource(archive_dir, orientation);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmpl, ec);
    UnregisterTempPath(id);
    throw;
  }
  source.temporary_id = id;
  source.kind = "points";
  source.title = fs::path(files.front()).filename().string() + (files.size() > 1 ? " + " + std::to_string(files.size() - 1) : "");
  source.temporary_dir = tmpl;
  return source;
}

// Every `every`-th record of a file of records (from the first), `piece` points a call, as the
// file's reader would give them.
class SampledRecords {
 public:
  SampledRecords(const std::string& path, const io::PointRecordLayout& layout, const LocalFrame& frame, uint64_t every)
      : path_(path), map_(std::make_shared<MappedFile>(path)), layout_(layout), frame_(frame), every_(every) {
    if (!io::HoldsRecords(*map_, layout_)) throw InputError(path, "", "the file does not hold its points");
    layout_.stride *= every;  // every k-th record: a layout of records k times as long
    layout_.count = (layout.count + every - 1) / every;
  }
  uint64_t count() const { return layout_.count; }
  PointCloud operator()(uint64_t first, uint64_t n) const {
    PointCloud c;
    c.schema.colors = layout_.rgb[0] >= 0;
    c.schema.position_type = ScalarType::kFloat64;
    c.SetSchema(c.schema);
    c.frame = frame_;
    c.Resize(n);
    const uint8_t* records = map_->data() + layout_.first_byte + first * layout_.stride;
    constexpr size_t kBlock = size_t{1} << 14;
    std::atomic<bool> finite{true};
    ParallelFor(size_t{0}, (n + kBlock - 1) / kBlock, [&](size_t b) {
      const size_t at = b * kBlock, m = std::min<size_t>(kBlock, n - at);
      bool ok = true;
      io::ForEachRecord(layout_, records + at * layout_.stride, m, 0, [&](size_t i, const Eigen::Vector3d& p, uint32_t rgb) {
        c.positions[at + i] = p;
        ok &= p.allFinite();
        if (c.schema.colors) c.colors[at + i] = {static_cast<uint8_t>(rgb >> 16), static_cast<uint8_t>(rgb >> 8), static_cast<uint8_t>(rgb)};
      });
      if (!ok) finite = false;
    });
    if (!finite) {  // as the file's reader says it: the record's number in the file
      size_t i = 0;
      while (c.positions[i].allFinite()) ++i;
      throw InputError(path_, "vertex " + std::to_string((first + i) * every_), "coordinate is NaN or infinite");
    }
    return c;
  }

 private:
  std::string path_;
  std::shared_ptr<MappedFile> map_;
  io::PointRecordLayout layout_;
  LocalFrame frame_;
  uint64_t every_;
};

}  // namespace

namespace {

// The files' record layouts and frames, and their points together; false when a file's points
// are not records.
bool RecordsOf(const std::vector<std::string>& files, const std::string& columns,
               std::vector<io::PointRecordLayout>* layouts, std::vector<LocalFrame>* frames, uint64_t* total) {
  io::PointReadOptions read;
  read.columns = columns;
  read.scalar_fields = false;
  *total = 0;
  for (const std::string& f : files) {
    const auto reader = io::OpenPointReader(f, read);
    const std::optional<io::PointRecordLayout> layout = reader->record_layout();
    if (!layout) return false;
    layouts->push_back(*layout);
    frames->push_back(reader->info().frame);
    *total += layout->count;
  }
  return true;
}

uint64_t EveryFor(uint64_t total, uint64_t points) { return total <= 2 * points ? 0 : (total + points - 1) / points; }

}  // namespace

uint64_t PreviewEvery(const std::vector<std::string>& files, const std::string& columns, uint64_t points) {
  CANDI_CHECK(points > 0) << "PreviewEvery: points 0";
  std::vector<io::PointRecordLayout> layouts;
  std::vector<LocalFrame> frames;
  uint64_t total = 0;
  return RecordsOf(files, columns, &layouts, &frames, &total) ? EveryFor(total, points) : 0;
}

std::optional<ViewerSource> PackPreviewSource(const std::vector<std::string>& files, const std::string& columns,
                                              const render::Orientation& orientation, uint64_t points,
                                              const ProgressCallback& progress) {
  CANDI_CHECK(points > 0) << "PackPreviewSource: points 0";
  std::vector<io::PointRecordLayout> layouts;
  std::vector<LocalFrame> frames;
  uint64_t total = 0;
  if (!RecordsOf(files, columns, &layouts, &frames, &total)) return std::nullopt;
  const uint64_t every = EveryFor(total, points);
  if (every == 0) return std::nullopt;
  ViewerSource source = PackIntoTemporary(files, orientation, [&](const std::string& archive_dir) {
    std::vector<render::PackInput> inputs;
    for (size_t k = 0; k < files.size(); ++k) {
      const SampledRecords sampled(files[k], layouts[k], frames[k], every);
      constexpr uint64_t kPiece = uint64_t{1} << 20;
      render::PackInput in = render::PackInputFromGenerator(
          files[k], sampled.count(), kPiece, [sampled](uint64_t piece, uint64_t n) { return sampled(piece * kPiece, n); });
      in.layer = fs::path(files[k]).stem().string();  // as PackInputFromFile names it
      inputs.push_back(std::move(in));
    }
    render::PackArchive(render::PackOptions(), inputs, archive_dir, progress);
  });
  source.preview_every = every;
  source.preview_points = total;
  return source;
}

ViewerSource PackViewerSource(const std::vector<std::string>& files, const std::string& columns,
                              const render::Orientation& orientation, const ProgressCallback& progress,
                              const FieldColouring& colour_by) {
  return PackIntoTemporary(files, orientation, [&](const std::string& archive_dir) {
    render::PackFiles(render::PackOptions(), files, columns, archive_dir, progress, colour_by);
  });
}

}  // namespace candi::view
