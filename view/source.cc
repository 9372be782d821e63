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
#include "render/build_record.h"
#include "render/view_json.h"

namespace candi::view {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

// What a visitor needs to tell measured from reconstructed: per layer its kind, method and
// sources (file names and SHA-256, not the build machine's paths), the CRS, the scene's licence
// and annotations.
json Provenance(const render::BuildRecord& r) {
  json out = json::object();
  if (!r.crs_definition.empty())
    out["crs"] = {{"definition", r.crs_definition}, {"label", r.crs_label}};
  if (!r.licence.empty()) out["licence"] = r.licence;
  if (!r.annotations.empty()) {
    json list = json::array();
    for (const render::BuildAnnotationRecord& a : r.annotations) {
      json e = {{"title", a.title}, {"text", a.text}, {"position", Vec(a.position)}};
      if (!a.view.empty()) e["view"] = a.view;
      if (a.camera) e["view"] = json::parse(render::ViewToJson(*a.camera));
      list.push_back(e);
    }
    out["annotations"] = list;
  }
  json layers = json::array();
  for (const render::BuildLayerRecord& l : r.layers) {
    json e = {{"name", l.name}, {"kind", l.kind}, {"method", l.method}, {"scanned", l.scanned}};
    const json crs = json::parse(l.crs_json);
    if (crs.is_object()) e["crs"] = crs;
    json sources = json::array();
    for (const render::BuildSourceRecord& src : l.sources) {
      json s = {{"file", fs::path(src.path).filename().string()}};
      if (!src.sha256.empty()) s["sha256"] = src.sha256;
      sources.push_back(s);
    }
    e["sources"] = sources;
    layers.push_back(e);
  }
  out["layers"] = layers;
  return out;
}

// A build's folder, as its record describes it: its layers, views and provenance, and the render
// settings the build resolved (older records have none: the viewer's defaults, the build's seed).
ViewerSource FromBuild(const fs::path& dir, const render::Orientation& orientation) {
  ViewerSource source;
  source.kind = "build";
  source.archive_dir = (dir / "archive").string();
  const render::BuildRecord record = render::ReadBuildRecord(dir.string());
  source.title = record.name;
  for (const render::BuildLayerRecord& l : record.layers) {
    source.layers.push_back({l.name, l.kind, l.points, l.opacity, l.highlight});
  }
  source.provenance_json = Provenance(record).dump();
  ViewSettings& v = source.settings;
  v.spbr.seed = record.seed;
  if (record.render) {
    const ImageSettings& r = *record.render;
    v.spbr.repeat_level = std::clamp(r.spbr.repeat_level, 1, kMaxViewRepeatLevel);
    v.spbr.seed = r.spbr.seed;
    v.background = r.background;
    v.brightness = r.brightness;
    source.first_view.width = std::clamp(r.width, 1, kMaxImageSide);
    source.first_view.height = std::clamp(r.height, 1, kMaxImageSide);
  }
  const render::Archive archive(source.archive_dir);
  const render::ArchiveManifest& m = archive.manifest();
  source.legend = m.colour_by;
  source.first_view =
      render::FirstView(m.bounds.Translated(m.frame.origin), source.first_view.width,
                        source.first_view.height, orientation);
  for (const render::BuildViewRecord& view : record.views) {
    const fs::path file = dir / "renders" / (view.name + ".view.json");
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) continue;
    source.views.push_back({view.name,
                            render::ParseView(ReadFileToString(file.string()), file.string()),
                            view.opaque});
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
             {{"repeat_level", settings.spbr.repeat_level},
              {"point_size", settings.spbr.point_size},
              {"background", {settings.background.r, settings.background.g, settings.background.b}},
              // (none is the gain 1, as the page sends it back)
              {"brightness",
               settings.brightness.automatic() ? json("auto") : json(settings.brightness.gain())},
              {"opaque", settings.spbr.opaque},
              {"seed", settings.spbr.seed},
              {"clip", ClipPlaneArrays(settings.clip)}}}};
  if (!provenance_json.empty()) s["provenance"] = json::parse(provenance_json);
  if (legend) s["legend"] = LegendJson(*legend);
  if (preview_every > 0) s["preview"] = {{"every", preview_every}, {"points", preview_points}};
  return s.dump(-1, ' ', false, json::error_handler_t::replace);
}

ViewerSource OpenViewerSource(const std::string& path, const render::Orientation& orientation) {
  const fs::path p(path);
  // A build directory, or a demo's output holding one in archive/ (what candi section opens).
  const std::string build = render::FindBuild(path);
  if (!build.empty()) return FromBuild(build, orientation);
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
