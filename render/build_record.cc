#include "render/build_record.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "render/archive.h"
#include "render/view_json.h"

namespace candi::render {

namespace {

using nlohmann::json;

// What every build's record has said of how to reproduce it.
constexpr const char* kSameBytes =
    "the same sources (their SHA-256 above), scene, seed, candi version and COLMAP build on the "
    "same machine give "
    "byte-identical layers/, archive/, renders/, meshlab/ and this file, for any thread count; run "
    "times are kept "
    "apart, in timings.json";
constexpr const char* kHow =
    "every random step draws from the scene's seed; parallel work is split and reduced in a fixed "
    "order; photos: "
    "COLMAP's image ids follow the photo names, candi matches the features exactly (brute force), "
    "COLMAP verifies "
    "and maps on one thread with its random seed fixed";
constexpr const char* kAcrossMachines =
    "not guaranteed: another CPU or C library can round floating point differently (COLMAP's SIFT, "
    "Ceres, libm), "
    "and one differing bit can change what COLMAP's mapper registers (README, Reproducibility)";
constexpr const char* kPointSourceId =
    "the layer's index in \"layers\" (0-based); the files' \"candi\" VLR names them";

// A number, NaN (undefined) as null.
json Figure(double v) { return std::isfinite(v) ? json(v) : json(); }
json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

// Reading: every access names the file and the JSON path of what is wrong.
class Reader {
 public:
  Reader(const json& j, std::string path, std::string at)
      : j_(j), path_(std::move(path)), at_(std::move(at)) {}
  bool Has(const char* key) const { return j_.is_object() && j_.contains(key); }
  Reader operator[](const char* key) const {
    if (!j_.is_object()) Fail("expected an object");
    if (!j_.contains(key))
      throw InputError(path_, at_.empty() ? "/" : at_, std::string("no \"") + key + "\"");
    return Reader(j_[key], path_, at_ + "/" + key);
  }
  Reader operator[](size_t i) const {
    return Reader(j_.at(i), path_, at_ + "/" + std::to_string(i));
  }
  size_t Size() const {
    if (!j_.is_array()) Fail("expected a list");
    return j_.size();
  }
  const json& raw() const { return j_; }
  std::string String() const {
    if (!j_.is_string()) Fail("expected a string");
    return j_.get<std::string>();
  }
  bool Bool() const {
    if (!j_.is_boolean()) Fail("expected true or false");
    return j_.get<bool>();
  }
  double Number() const {
    if (!j_.is_number()) Fail("expected a number");
    return j_.get<double>();
  }
  double NumberOrNull() const { return j_.is_null() ? NAN : Number(); }
  uint64_t Count() const {
    if (!j_.is_number_unsigned()) Fail("expected a whole number >= 0");
    return j_.get<uint64_t>();
  }
  Eigen::Vector3d Vector() const {
    if (!j_.is_array() || j_.size() != 3) Fail("expected [x, y, z]");
    return {(*this)[size_t{0}].Number(), (*this)[1].Number(), (*this)[2].Number()};
  }
  std::vector<std::string> Strings() const {
    std::vector<std::string> out;
    for (size_t i = 0; i < Size(); ++i) out.push_back((*this)[i].String());
    return out;
  }
  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path_, at_.empty() ? "/" : at_, what);
  }

 private:
  const json& j_;
  std::string path_, at_;
};

json LayerJson(const BuildLayerRecord& l) {
  json sources = json::array();
  for (const BuildSourceRecord& s : l.sources)
    sources.push_back({{"path", s.path}, {"sha256", s.sha256}, {"bytes", s.bytes}});
  json matrix = json::array();
  for (int r = 0; r < 4; ++r) {
    const Eigen::Matrix4d& m = l.world_from_layer;
    matrix.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  }
  json replaced_by = json::object();
  for (const auto& [name, n] : l.replaced_by) replaced_by[name] = n;
  return {{"name", l.name},
          {"kind", l.kind},
          {"scanned", l.scanned},
          {"method", l.method},
          {"parameters", json::parse(l.parameters_json)},
          {"sources", sources},
          {"world_from_layer", matrix},
          {"opacity", l.opacity},
          {"highlight", l.highlight},
          {"points", l.points},
          {"dropped_nan", l.dropped_nan},
          {"replaces", l.replaces},
          {"replaced_by", replaced_by},
          {"crs", json::parse(l.crs_json)},
          {"file", l.file},
          {"resumed", l.resumed}};
}

BuildLayerRecord LayerFrom(const Reader& r) {
  BuildLayerRecord l;
  l.name = r["name"].String();
  l.file = r["file"].String();
  if (r.Has("kind")) l.kind = r["kind"].String();
  if (r.Has("scanned")) l.scanned = r["scanned"].Bool();
  if (r.Has("method")) l.method = r["method"].String();
  if (r.Has("parameters")) l.parameters_json = r["parameters"].raw().dump();
  if (r.Has("sources")) {
    const Reader s = r["sources"];
    for (size_t i = 0; i < s.Size(); ++i) {
      BuildSourceRecord src;
      src.path = s[i]["path"].String();
      if (s[i].Has("sha256")) src.sha256 = s[i]["sha256"].String();
      if (s[i].Has("bytes")) src.bytes = s[i]["bytes"].Count();
      l.sources.push_back(src);
    }
  }
  if (r.Has("world_from_layer")) {
    const Reader m = r["world_from_layer"];
    if (m.Size() != 4) m.Fail("expected 4 rows");
    for (int i = 0; i < 4; ++i) {
      if (m[i].Size() != 4) m[i].Fail("expected 4 numbers");
      for (int c = 0; c < 4; ++c) l.world_from_layer(i, c) = m[i][c].Number();
    }
  }
  if (r.Has("opacity")) l.opacity = r["opacity"].Number();
  if (r.Has("highlight")) l.highlight = r["highlight"].Bool();
  if (r.Has("points")) l.points = r["points"].Count();
  if (r.Has("dropped_nan")) l.dropped_nan = r["dropped_nan"].Count();
  if (r.Has("replaces")) l.replaces = r["replaces"].Strings();
  if (r.Has("replaced_by")) {
    const Reader b = r["replaced_by"];
    if (!b.raw().is_object()) b.Fail("expected an object");
    for (auto it = b.raw().begin(); it != b.raw().end(); ++it) {
      l.replaced_by.push_back({it.key(), b[it.key().c_str()].Count()});
    }
  }
  if (r.Has("crs")) l.crs_json = r["crs"].raw().dump();
  if (r.Has("resumed")) l.resumed = r["resumed"].Bool();
  return l;
}

// A comparison's entry; `resumed` only in the record (a checkpoint keeps the entry without it).
json ComparisonJson(const BuildComparisonRecord& c, bool with_resumed) {
  const std::string base = "compare/" + c.name + ".ply";
  json e = {{"name", c.name},
            {"compared", c.compared},
            {"reference", c.reference},
            {"reference_kind", c.reference_is_layer ? "layer" : "file"},
            {"method", c.method},
            {"signed", c.is_signed},
            {"files",
             {{"cloud", base},
              {"summary", base + ".compare.json"},
              {"histogram", base + ".histogram.svg"},
              {"report", base + ".report.md"}}},
            {"count", c.count},
            {"defined", c.defined},
            {"undefined", c.undefined},
            {"mean_m", Figure(c.mean)},
            {"std_m", Figure(c.std)},
            {"rms_m", Figure(c.rms)},
            {"mean_abs_m", Figure(c.mean_abs)},
            {"tolerance_m", c.tolerance},
            {"within_tolerance", Figure(c.within_tolerance)}};
  if (c.significant) e["significant"] = *c.significant;
  if (with_resumed) e["resumed"] = c.resumed;
  return e;
}

BuildComparisonRecord ComparisonFrom(const Reader& r) {
  BuildComparisonRecord c;
  c.name = r["name"].String();
  c.compared = r["compared"].String();
  c.reference = r["reference"].String();
  c.reference_is_layer = r["reference_kind"].String() == "layer";
  c.method = r["method"].String();
  c.is_signed = r["signed"].Bool();
  c.count = r["count"].Count();
  c.defined = r["defined"].Count();
  c.undefined = r["undefined"].Count();
  c.mean = r["mean_m"].NumberOrNull();
  c.std = r["std_m"].NumberOrNull();
  c.rms = r["rms_m"].NumberOrNull();
  c.mean_abs = r["mean_abs_m"].NumberOrNull();
  c.tolerance = r["tolerance_m"].Number();
  c.within_tolerance = r["within_tolerance"].NumberOrNull();
  if (r.Has("significant")) c.significant = r["significant"].Count();
  if (r.Has("resumed")) c.resumed = r["resumed"].Bool();
  return c;
}

json CopcFileJson(const BuildCopcFileRecord& f) {
  json j = {{"path", f.path}, {"points", f.points}, {"bytes", f.bytes}};
  if (!f.layer.empty()) j["name"] = f.layer;
  return j;
}

BuildCopcFileRecord CopcFileFrom(const Reader& r) {
  BuildCopcFileRecord f;
  f.path = r["path"].String();
  f.points = r["points"].Count();
  f.bytes = r["bytes"].Count();
  if (r.Has("name")) f.layer = r["name"].String();
  return f;
}

// The files of a COPC record ({"layers": [...], "scene": {...}}).
json CopcFilesJson(const BuildCopcRecord& copc) {
  json c = {{"layers", json::array()}};
  for (const BuildCopcFileRecord& f : copc.layers) c["layers"].push_back(CopcFileJson(f));
  if (copc.scene) c["scene"] = CopcFileJson(*copc.scene);
  return c;
}

BuildCopcRecord CopcFrom(const Reader& c) {
  BuildCopcRecord copc;
  const Reader files = c["layers"];
  for (size_t k = 0; k < files.Size(); ++k) copc.layers.push_back(CopcFileFrom(files[k]));
  if (c.Has("scene")) copc.scene = CopcFileFrom(c["scene"]);
  if (c.Has("scale_m")) copc.scale_m = c["scale_m"].Number();
  if (c.Has("resumed")) copc.resumed = c["resumed"].Bool();
  return copc;
}

json Parse(const std::string& text, const std::string& path) {
  try {
    return json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(path, "byte " + std::to_string(e.byte),
                     std::string("not valid JSON: ") + e.what());
  }
}

json RenderJson(const ImageSettings& r) {
  const Brightness& b = r.brightness;
  return {{"repeat_level", r.spbr.repeat_level},
          {"seed", r.spbr.seed},
          {"width", r.width},
          {"height", r.height},
          {"background", {r.background.r, r.background.g, r.background.b}},
          {"brightness", b.automatic() || b.none() ? json(b.ToString()) : json(b.gain())}};
}

ImageSettings RenderFrom(const Reader& r) {
  ImageSettings out;
  out.spbr.repeat_level = static_cast<int>(r["repeat_level"].Count());
  out.spbr.seed = r["seed"].Count();
  out.width = static_cast<int>(r["width"].Count());
  out.height = static_cast<int>(r["height"].Count());
  const Reader b = r["background"];
  if (b.Size() != 3) b.Fail("expected [r, g, b]");
  uint64_t c[3];
  for (size_t i = 0; i < 3; ++i) {
    c[i] = b[i].Count();
    if (c[i] > 255) b[i].Fail("expected 0 to 255");
  }
  out.background = {static_cast<uint8_t>(c[0]), static_cast<uint8_t>(c[1]),
                    static_cast<uint8_t>(c[2])};
  const Reader g = r["brightness"];
  try {
    out.brightness =
        g.raw().is_string() ? Brightness::Parse(g.String()) : Brightness::Gain(g.Number());
  } catch (const std::invalid_argument&) {
    g.Fail(std::string("expected ") + Brightness::Rule());
  }
  if (out.spbr.repeat_level < 1 || out.spbr.repeat_level > kMaxRepeatLevel)
    r["repeat_level"].Fail("out of range");
  if (out.width < 1 || out.width > kMaxImageSize) r["width"].Fail("out of range");
  if (out.height < 1 || out.height > kMaxImageSize) r["height"].Fail("out of range");
  return out;
}

}  // namespace

std::string BuildRecord::ToJson() const {
  json layers_json = json::array();
  for (const BuildLayerRecord& l : layers) layers_json.push_back(LayerJson(l));
  json views_json = json::array();
  for (const BuildViewRecord& v : views) {
    json alphas = json::object();
    for (const auto& [layer, alpha] : v.opacity) alphas[layer] = alpha;
    views_json.push_back({{"name", v.name},
                          {"png", v.png},
                          {"opaque", v.opaque},
                          {"opacity", alphas},
                          {"resumed", v.resumed}});
  }
  json p = {{"candi_version", candi_version},
            {"scene", {{"path", scene_path}, {"sha256", scene_sha256}}},
            {"name", name},
            {"seed", seed},
            {"frame", {{"origin", Vec(origin)}}},
            {"crs", crs_definition.empty()
                        ? json()
                        : json({{"definition", crs_definition}, {"label", crs_label}})},
            {"points", points},
            {"layers", layers_json},
            {"archive", "archive"},
            {"pack_resumed", pack_resumed},
            {"views", views_json},
            {"meshlab", "meshlab/scene.mlp"},
            {"reproducibility",
             {{"seed", seed},
              {"same_bytes", kSameBytes},
              {"how", kHow},
              {"across_machines", kAcrossMachines}}}};
  if (render) p["render"] = RenderJson(*render);
  // What a published page shows besides the layers (only when the scene gives them).
  if (!licence.empty()) p["licence"] = licence;
  if (!annotations.empty()) {
    json list = json::array();
    for (const BuildAnnotationRecord& a : annotations) {
      json e = {{"title", a.title}, {"text", a.text}, {"position", Vec(a.position)}};
      if (!a.view.empty()) e["view"] = a.view;
      if (a.camera) e["view"] = json::parse(ViewToJson(*a.camera));
      list.push_back(e);
    }
    p["annotations"] = list;
  }
  if (!comparisons.empty()) {
    json list = json::array();
    for (const BuildComparisonRecord& c : comparisons) list.push_back(ComparisonJson(c, true));
    p["comparisons"] = list;
  }
  if (copc) {
    json c = CopcFilesJson(*copc);
    c["point_source_id"] = kPointSourceId;
    c["scale_m"] = copc->scale_m;
    c["resumed"] = copc->resumed;
    p["copc"] = c;
  }
  return p.dump(2) + "\n";
}

BuildRecord BuildRecord::FromJson(const std::string& text, const std::string& path) {
  const json j = Parse(text, path);
  const Reader r(j, path, "");
  if (!j.is_object()) r.Fail("expected an object: not the archive.json of a candi build");
  // What every build's record has had: its name, CRS, frame and layers (each with its file).
  BuildRecord b;
  b.name = r["name"].String();
  const Reader crs = r["crs"];
  b.origin = r["frame"]["origin"].Vector();
  if (r.Has("candi_version")) b.candi_version = r["candi_version"].String();
  if (r.Has("scene")) {
    const Reader s = r["scene"];
    if (s.Has("path")) b.scene_path = s["path"].String();
    if (s.Has("sha256")) b.scene_sha256 = s["sha256"].String();
  }
  if (r.Has("seed")) b.seed = r["seed"].Count();
  if (!crs.raw().is_null()) {
    b.crs_definition = crs["definition"].String();
    if (crs.Has("label")) b.crs_label = crs["label"].String();
  }
  if (r.Has("points")) b.points = r["points"].Count();
  const Reader layers = r["layers"];
  for (size_t k = 0; k < layers.Size(); ++k) b.layers.push_back(LayerFrom(layers[k]));
  if (r.Has("pack_resumed")) b.pack_resumed = r["pack_resumed"].Bool();
  if (r.Has("views")) {
    const Reader views = r["views"];
    for (size_t k = 0; k < views.Size(); ++k) {
      const Reader v = views[k];
      BuildViewRecord view;
      view.name = v["name"].String();
      if (v.Has("png")) view.png = v["png"].String();
      if (v.Has("opaque")) view.opaque = v["opaque"].Bool();
      if (v.Has("opacity")) {
        const Reader o = v["opacity"];
        if (!o.raw().is_object()) o.Fail("expected an object");
        for (auto it = o.raw().begin(); it != o.raw().end(); ++it) {
          view.opacity.push_back({it.key(), o[it.key().c_str()].Number()});
        }
      }
      if (v.Has("resumed")) view.resumed = v["resumed"].Bool();
      b.views.push_back(view);
    }
  }
  if (r.Has("render")) b.render = RenderFrom(r["render"]);
  if (r.Has("licence")) b.licence = r["licence"].String();
  if (r.Has("annotations")) {
    const Reader list = r["annotations"];
    for (size_t k = 0; k < list.Size(); ++k) {
      const Reader a = list[k];
      BuildAnnotationRecord e;
      e.title = a["title"].String();
      if (a.Has("text")) e.text = a["text"].String();
      e.position = a["position"].Vector();
      if (a.Has("view")) {
        if (a["view"].raw().is_string())
          e.view = a["view"].String();
        else if (a["view"].raw().is_object())
          e.camera = ParseView(a["view"].raw().dump(), path);
        else
          a["view"].Fail("expected a view's name or a camera");
      }
      b.annotations.push_back(e);
    }
  }
  if (r.Has("comparisons")) {
    const Reader list = r["comparisons"];
    for (size_t k = 0; k < list.Size(); ++k) b.comparisons.push_back(ComparisonFrom(list[k]));
  }
  if (r.Has("copc")) b.copc = CopcFrom(r["copc"]);
  return b;
}

std::string ComparisonToJson(const BuildComparisonRecord& c) {
  return ComparisonJson(c, false).dump();
}

BuildComparisonRecord ComparisonFromJson(const std::string& text, const std::string& path) {
  const json j = Parse(text, path);
  return ComparisonFrom(Reader(j, path, ""));
}

std::string CopcFilesToJson(const BuildCopcRecord& copc) { return CopcFilesJson(copc).dump(); }

BuildCopcRecord CopcFilesFromJson(const std::string& text, const std::string& path) {
  const json j = Parse(text, path);
  return CopcFrom(Reader(j, path, ""));
}

std::string FindBuild(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const fs::path& build : {fs::path(path), fs::path(path) / "archive"}) {
    if (fs::is_regular_file(build / kBuildRecord, ec) && IsArchive((build / "archive").string()))
      return build.string();
  }
  return "";
}

BuildRecord ReadBuildRecord(const std::string& build_dir) {
  namespace fs = std::filesystem;
  const std::string path = (fs::path(build_dir) / kBuildRecord).string();
  std::error_code ec;
  if (!fs::is_directory(build_dir, ec)) {
    throw InputError(build_dir, "", "not a folder (a finished candi build's, with archive.json)");
  }
  if (!fs::exists(path, ec))
    throw InputError(build_dir, "", "no archive.json: not a finished candi build");
  return BuildRecord::FromJson(ReadFileToString(path), path);
}

void WriteBuildRecord(const std::string& build_dir, const BuildRecord& record) {
  WriteFileAtomic((std::filesystem::path(build_dir) / kBuildRecord).string(), record.ToJson());
}

}  // namespace candi::render
