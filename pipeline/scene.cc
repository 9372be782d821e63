#include "pipeline/scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/crs.h"
#include "render/view_json.h"

namespace candi::pipeline {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// A JSON value with its JSON path, for error messages naming the culprit.
class Node {
 public:
  Node(const std::string& file, const json& j, std::string path) : file_(&file), j_(&j), path_(std::move(path)) {}

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(*file_, path_.empty() ? "/" : path_, what);
  }
  const json& raw() const { return *j_; }
  const std::string& path() const { return path_; }
  const std::string& file() const { return *file_; }

  // An object whose keys are all in `known`.
  void ExpectObject(const std::set<std::string>& known) const {
    if (!j_->is_object()) Fail("expected an object");
    for (auto it = j_->begin(); it != j_->end(); ++it) {
      if (known.count(it.key())) continue;
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : " ") + k;
      Node(*file_, it.value(), path_ + "/" + it.key()).Fail("unknown key (known: " + list + ")");
    }
  }
  bool Has(const std::string& key) const { return j_->contains(key); }
  Node operator[](const std::string& key) const { return Node(*file_, j_->at(key), path_ + "/" + key); }
  Node operator[](size_t i) const { return Node(*file_, (*j_)[i], path_ + "/" + std::to_string(i)); }
  size_t ArraySize() const {
    if (!j_->is_array()) Fail("expected an array");
    return j_->size();
  }

  std::string String() const {
    if (!j_->is_string()) Fail("expected a string");
    return j_->get<std::string>();
  }
  bool Bool() const {
    if (!j_->is_boolean()) Fail("expected true or false");
    return j_->get<bool>();
  }
  double Number(double lo, double hi, bool open_lo = false) const {
    if (!j_->is_number()) Fail("expected a number");
    const double v = j_->get<double>();
    if (!std::isfinite(v)) Fail("not a finite number");
    if (v < lo || v > hi || (open_lo && v == lo))
      Fail("out of range: " + Format(v) + " is not in " + (open_lo ? "(" : "[") + Format(lo) + ", " + Format(hi) + "]");
    return v;
  }
  long long Integer(long long lo, long long hi) const {
    if (!j_->is_number_integer()) Fail("expected an integer");
    const long long v = j_->get<long long>();
    if (v < lo || v > hi) Fail("out of range: " + std::to_string(v) + " is not in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  Eigen::Vector3d Vec3() const {
    if (!j_->is_array() || j_->size() != 3) Fail("expected an array of three numbers");
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) v[k] = (*this)[k].Number(-1e300, 1e300);
    return v;
  }
  Rgb8 Colour() const {
    if (!j_->is_array() || j_->size() != 3) Fail("expected [r, g, b] with values 0-255");
    Rgb8 c;
    c.r = static_cast<uint8_t>((*this)[0].Integer(0, 255));
    c.g = static_cast<uint8_t>((*this)[1].Integer(0, 255));
    c.b = static_cast<uint8_t>((*this)[2].Integer(0, 255));
    return c;
  }
  // A coordinate reference system PROJ reads (checked here, so a typo fails before any work).
  std::string Crs() const {
    const std::string text = String();
    try {
      io::DescribeCrs(text, *file_);
    } catch (const InputError& e) {
      const std::string what = e.what();
      const size_t at = what.find("PROJ");
      Fail(at == std::string::npos ? what : what.substr(at));
    }
    return text;
  }
  // A path relative to the scene's folder, made absolute; `must_exist` checks it (file or folder).
  std::string Path(bool must_exist, bool folder = false) const {
    const std::string text = String();
    if (text.empty()) Fail("empty path");
    fs::path p(text);
    if (p.is_relative()) p = fs::path(*file_).parent_path() / p;
    p = p.lexically_normal();
    if (must_exist) {
      std::error_code ec;
      const fs::file_status st = fs::status(p, ec);
      if (!fs::exists(st)) Fail("no such " + std::string(folder ? "folder" : "file") + ": " + p.string());
      if (folder && !fs::is_directory(st)) Fail("not a folder: " + p.string());
      if (!folder && fs::is_directory(st)) Fail("a folder, expected a file: " + p.string());
    }
    return p.string();
  }

 private:
  static std::string Format(double v) {
    char b[32];
    std::snprintf(b, sizeof(b), "%g", v);
    return b;
  }
  const std::string* file_;
  const json* j_;
  std::string path_;
};

bool ValidName(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) return false;
  return true;
}

Sim3 ParseTransform(const Node& n) {
  if (n.raw().is_object() && n.Has("matrix")) {
    n.ExpectObject({"matrix"});
    const Node m = n["matrix"];
    if (m.ArraySize() != 4) m.Fail("expected 4 rows");
    Eigen::Matrix4d a;
    for (int r = 0; r < 4; ++r) {
      if (m[r].ArraySize() != 4) m[r].Fail("expected 4 numbers");
      for (int c = 0; c < 4; ++c) a(r, c) = m[r][c].Number(-1e300, 1e300);
    }
    if ((a.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12)
      m[3].Fail("the last row must be 0 0 0 1");
    try {
      return Sim3FromMatrix(a, 1e-6);
    } catch (const std::invalid_argument& e) {
      m.Fail(std::string("not a similarity transform: ") + e.what());
    }
  }
  n.ExpectObject({"scale", "rotation_deg", "translation"});
  double scale = 1;
  Eigen::Vector3d angles = Eigen::Vector3d::Zero(), t = Eigen::Vector3d::Zero();
  if (n.Has("scale")) scale = n["scale"].Number(0, 1e9, true);
  if (n.Has("rotation_deg")) angles = n["rotation_deg"].Vec3() * (M_PI / 180.0);
  if (n.Has("translation")) t = n["translation"].Vec3();
  const Eigen::Quaterniond q = Eigen::AngleAxisd(angles.z(), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(angles.y(), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(angles.x(), Eigen::Vector3d::UnitX());
  return Sim3(scale, q, t);
}

LayerKind ParseKind(const Node& n) {
  const std::string k = n.String();
  if (k == "points") return LayerKind::kPoints;
  if (k == "foundation") return LayerKind::kFoundation;
  if (k == "relief") return LayerKind::kRelief;
  if (k == "photogrammetry") return LayerKind::kPhotogrammetry;
  n.Fail("unknown kind \"" + k + "\" (known: points foundation relief photogrammetry)");
}

SceneLayer ParseLayer(const Node& n) {
  if (!n.raw().is_object()) n.Fail("expected an object");
  if (!n.Has("name")) n.Fail("missing key \"name\"");
  if (!n.Has("kind")) n.Fail("missing key \"kind\"");
  SceneLayer l;
  l.key_json = n.raw().dump();
  l.name = n["name"].String();
  if (!ValidName(l.name)) n["name"].Fail("a layer name is 1-64 characters of A-Z a-z 0-9 _ - (it names files)");
  l.kind = ParseKind(n["kind"]);
  std::set<std::string> known = {"name", "kind", "world_from_layer", "crs", "color", "opacity", "highlight",
                                 "replaces", "replace_voxel"};
  switch (l.kind) {
    case LayerKind::kPoints: known.insert({"file", "columns"}); break;
    case LayerKind::kFoundation:
      known.insert({"dxf", "sections", "samples_per_side", "angular_steps", "density", "count", "mode"});
      break;
    case LayerKind::kRelief: known.insert({"panels", "model", "placement", "width_m"}); break;
    case LayerKind::kPhotogrammetry:
      known.insert({"dense", "workspace", "images", "targets", "targets_crs", "picks", "max_image_size",
                     "max_features", "resolution_scale", "iterations", "chunks", "matching", "priors"});
      break;
  }
  n.ExpectObject(known);
  if (n.Has("world_from_layer")) l.world_from_layer = ParseTransform(n["world_from_layer"]);
  if (n.Has("crs")) l.crs = n["crs"].String() == "scene" ? "scene" : n["crs"].Crs();
  if (n.Has("color")) l.color = n["color"].Colour();
  if (n.Has("opacity")) l.opacity = n["opacity"].Number(0, 1, true);
  if (n.Has("highlight")) l.highlight = n["highlight"].Bool();
  if (n.Has("replaces")) {
    const Node r = n["replaces"];
    for (size_t i = 0; i < r.ArraySize(); ++i) l.replaces.push_back(r[i].String());  // checked by LoadScene
  }
  if (n.Has("replace_voxel")) {
    if (!n.Has("replaces")) n["replace_voxel"].Fail("only with \"replaces\"");
    l.replace_voxel = n["replace_voxel"].Number(0, 1000, true);
  }
  auto require = [&](const char* key) {
    if (!n.Has(key)) n.Fail(std::string("a ") + LayerKindName(l.kind) + " layer needs \"" + key + "\"");
    return n[key];
  };
  switch (l.kind) {
    case LayerKind::kPoints:
      l.file = require("file").Path(true);
      if (n.Has("columns")) l.columns = n["columns"].String();
      break;
    case LayerKind::kFoundation:
      l.dxf = require("dxf").Path(true);
      if (n.Has("sections")) {
        const Node s = n["sections"];
        for (size_t i = 0; i < s.ArraySize(); ++i) l.foundation.layers.push_back(s[i].String());
      }
      if (n.Has("samples_per_side")) {
        l.foundation.surface.profile.samples_per_side =
            static_cast<int>(n["samples_per_side"].Integer(2, 1000000));
      }
      if (n.Has("angular_steps")) {
        l.foundation.surface.revolve.angular_steps =
            static_cast<int>(n["angular_steps"].Integer(2, 1000000));
      }
      if (n.Has("density") && n.Has("count")) n["count"].Fail("give one of \"density\" and \"count\"");
      if (n.Has("density")) l.foundation.sample.density = n["density"].Number(0, 1e9, true);
      if (n.Has("count")) {
        l.foundation.sample.count = static_cast<uint64_t>(n["count"].Integer(1, 10000000000LL));
        l.foundation.sample.density = 0;
      }
      if (n.Has("mode")) {
        const std::string mode = n["mode"].String();
        if (mode != "auto" && mode != "blend" && mode != "sweep")
          n["mode"].Fail("expected auto, blend or sweep");
        l.foundation.surface.revolve.mode = mesh::ParseRevolveMode(mode);
      }
      break;
    case LayerKind::kRelief: {
      const Node panels = require("panels");
      if (panels.ArraySize() == 0) panels.Fail("no panels");
      std::set<std::string> ids;
      bool photos = false;
      for (size_t i = 0; i < panels.ArraySize(); ++i) {
        const Node p = panels[i];
        p.ExpectObject({"id", "photo", "points", "native_resolution"});
        if (!p.Has("id")) p.Fail("missing key \"id\"");
        ReliefPanelSpec spec;
        spec.id = p["id"].String();
        if (!ValidName(spec.id)) p["id"].Fail("a panel id is 1-64 characters of A-Z a-z 0-9 _ -");
        if (!ids.insert(spec.id).second) p["id"].Fail("panel id \"" + spec.id + "\" repeats");
        if (p.Has("photo") == p.Has("points")) p.Fail("give exactly one of \"photo\" and \"points\"");
        if (p.Has("photo")) spec.photo = p["photo"].Path(true), photos = true;
        else spec.points = p["points"].Path(true);
        if (p.Has("native_resolution")) {
          if (!p.Has("photo")) p["native_resolution"].Fail("only for panels given by a photo");
          spec.native_resolution = p["native_resolution"].Bool();
        }
        l.panels.push_back(spec);
      }
      if (photos) l.model = require("model").Path(true);
      else if (n.Has("model")) l.model = n["model"].Path(true);
      l.placement = require("placement").Path(true);
      if (n.Has("width_m")) l.width_m = n["width_m"].Number(0, 1000, true);
      break;
    }
    case LayerKind::kPhotogrammetry: {
      const int sources = n.Has("dense") + n.Has("workspace") + n.Has("images");
      if (sources != 1) n.Fail("a photogrammetry layer needs exactly one of \"dense\", \"workspace\" and \"images\"");
      if (n.Has("dense")) l.dense = n["dense"].Path(true);
      else if (n.Has("workspace")) l.workspace = n["workspace"].Path(true, true);
      else l.images = n["images"].Path(true, true);
      if (n.Has("targets")) l.targets = n["targets"].Path(true);
      if (n.Has("targets_crs")) {
        if (!n.Has("targets")) n["targets_crs"].Fail("only with \"targets\"");
        l.targets_crs = n["targets_crs"].Crs();
      }
      if (n.Has("picks")) {
        if (!n.Has("targets")) n["picks"].Fail("picks need \"targets\" (the surveyed coordinates)");
        if (n.Has("dense")) n["picks"].Fail("picks need the cameras: give \"images\" or \"workspace\", not \"dense\"");
        l.picks = n["picks"].Path(true);
      }
      for (const char* key : {"max_image_size", "max_features", "chunks", "matching", "priors"})
        if (n.Has(key) && !n.Has("images")) n[key].Fail("only with \"images\" (it sets structure from motion)");
      if (n.Has("chunks") && n["chunks"].Bool()) {
        // A campaign: each session folder mapped apart and tied by the targets it sees.
        if (!n.Has("picks")) n["chunks"].Fail("mapping in chunks ties them by \"targets\" and their \"picks\"");
        if (n.Has("targets_crs")) n["targets_crs"].Fail("not with \"chunks\": the chunks are tied in the targets' own CRS");
        l.sfm.chunks.targets = l.targets;
        l.sfm.chunks.picks = l.picks;
      }
      if (n.Has("matching")) {
        try {
          l.sfm.pairs.strategy = photogrammetry::ParsePairStrategy(n["matching"].String());
        } catch (const std::invalid_argument& e) {
          n["matching"].Fail(e.what());
        }
      }
      if (n.Has("priors")) l.sfm.priors = n["priors"].Path(true);
      if (n.Has("max_image_size"))
        l.sfm.max_image_size = static_cast<int>(n["max_image_size"].Integer(64, 100000));
      if (n.Has("max_features"))
        l.sfm.max_features = static_cast<int>(n["max_features"].Integer(64, 1000000));
      for (const char* key : {"resolution_scale", "iterations"})
        if (n.Has(key) && n.Has("dense")) n[key].Fail("dense stereo options need \"images\" or \"workspace\"");
      if (n.Has("resolution_scale"))
        l.stereo.resolution_scale = n["resolution_scale"].Number(0, 1, true);
      if (n.Has("iterations"))
        l.stereo.iterations = static_cast<int>(n["iterations"].Integer(1, 100));
      break;
    }
  }
  return l;
}

// An inline camera (render/view_json.h's format, world coordinates).
render::Camera InlineCamera(const Node& n, const std::string& scene_path) {
  try {
    return render::ParseView(n.raw().dump(), scene_path);
  } catch (const InputError& e) {
    n.Fail(std::string("not a camera: ") + e.what());
  }
}

SceneView ParseSceneView(const Node& n, const std::set<std::string>& layer_names) {
  n.ExpectObject({"name", "camera", "opaque", "layers", "focus", "focus_opacity", "dim", "opacity", "point_size"});
  SceneView v;
  v.key_json = n.raw().dump();
  if (!n.Has("name")) n.Fail("missing key \"name\"");
  v.name = n["name"].String();
  if (!ValidName(v.name)) n["name"].Fail("a view name is 1-64 characters of A-Z a-z 0-9 _ - (it names the PNG)");
  if (n.Has("camera")) {
    const Node c = n["camera"];
    if (c.raw().is_string()) v.camera_file = c.Path(true);
    else if (c.raw().is_object())
      v.camera = InlineCamera(c, n.file());
    else c.Fail("expected a view file or an inline view object");
  }
  if (n.Has("opaque")) v.opaque = n["opaque"].Bool();
  auto check_layer = [&](const Node& s) {
    const std::string name = s.String();
    if (!layer_names.count(name)) s.Fail("no layer named \"" + name + "\"");
    return name;
  };
  if (n.Has("layers")) {
    const Node s = n["layers"];
    std::set<std::string> seen;
    for (size_t i = 0; i < s.ArraySize(); ++i) {
      const std::string name = check_layer(s[i]);
      if (!seen.insert(name).second) s[i].Fail("layer \"" + name + "\" is listed twice");
      v.layers.push_back(name);
    }
    if (v.layers.empty()) s.Fail("no layers");
  }
  if (n.Has("focus")) v.focus = n["focus"].Bool();
  if (n.Has("focus_opacity")) v.focus_opacity = n["focus_opacity"].Number(0, 1, true);
  if (n.Has("dim")) v.dim = n["dim"].Number(0, 1, true);
  if (n.Has("point_size")) v.point_size = n["point_size"].Number(1, 32);
  if (n.Has("opacity")) {
    const Node o = n["opacity"];
    if (!o.raw().is_object()) o.Fail("expected an object of layer name -> opacity");
    for (auto it = o.raw().begin(); it != o.raw().end(); ++it) {
      const Node value = o[it.key()];
      if (!layer_names.count(it.key())) value.Fail("no layer named \"" + it.key() + "\"");
      v.opacity[it.key()] = value.Number(0, 1, true);
    }
  }
  return v;
}

// A name-to-value choice of the scene file (a method, a model, an orientation): the parse
// function's std::invalid_argument becomes an error naming the key.
template <typename T>
T Choice(const Node& n, T (*parse)(const std::string&)) {
  const std::string text = n.String();
  try {
    return parse(text);
  } catch (const std::invalid_argument& e) {
    n.Fail(e.what());
  }
}

// The keys of a comparison that only one method reads.
const std::map<std::string, compare::Method>& MethodKeys() {
  static const std::map<std::string, compare::Method> keys = {
      {"model", compare::Method::kC2C},
      {"model_neighbours", compare::Method::kC2C},
      {"unsigned", compare::Method::kC2M},
      {"normal_scale", compare::Method::kM3C2},
      {"projection_scale", compare::Method::kM3C2},
      {"max_depth", compare::Method::kM3C2},
      {"registration_error", compare::Method::kM3C2},
      {"min_points", compare::Method::kM3C2},
      {"orientation", compare::Method::kM3C2}};
  return keys;
}

// The method's settings of a comparison (each key checked against the method first).
void ParseMethodSettings(const Node& n, compare::DeviationOptions* d) {
  for (const auto& [key, method] : MethodKeys()) {
    if (n.Has(key) && method != d->method)
      n[key].Fail("only with \"method\": \"" + compare::MethodName(method) + "\"");
  }
  if (n.Has("model")) d->c2c.local_model = Choice(n["model"], compare::ParseLocalModel);
  if (n.Has("model_neighbours")) d->c2c.model_neighbours = static_cast<int>(n["model_neighbours"].Integer(3, 1000));
  if (n.Has("unsigned")) d->c2m.signed_distance = !n["unsigned"].Bool();
  if (n.Has("normal_scale")) d->m3c2.normal_scale = n["normal_scale"].Number(0, 1e9);
  if (n.Has("projection_scale")) d->m3c2.projection_scale = n["projection_scale"].Number(0, 1e9);
  if (n.Has("max_depth")) d->m3c2.max_depth = n["max_depth"].Number(0, 1e9);
  if (n.Has("registration_error")) d->m3c2.registration_error = n["registration_error"].Number(0, 1e9);
  if (n.Has("min_points")) d->m3c2.min_points = static_cast<int>(n["min_points"].Integer(2, 1000000));
  if (n.Has("orientation")) d->m3c2.orientation = Choice(n["orientation"], compare::ParseNormalOrientation);
  try {
    d->Check();  // the rules between settings (a quadric needs 6 neighbours)
  } catch (const std::invalid_argument& e) {
    n.Fail(e.what());
  }
}

// The reference of a comparison: a layer's name, or a file relative to the scene's folder.
void ParseReference(const Node& n, const std::set<std::string>& layer_names, SceneComparison* c) {
  const std::string text = n.String();
  if (layer_names.count(text)) {
    if (text == c->compared) n.Fail("layer \"" + text + "\" compared to itself");
    if (c->deviation.method == compare::Method::kC2M)
      n.Fail("c2m compares to a mesh: give a mesh file (PLY or OBJ), not the layer \"" + text + "\"");
    c->reference_layer = text;
    return;
  }
  c->reference_file = n.Path(false);
  std::error_code ec;
  if (!fs::is_regular_file(c->reference_file, ec))
    n.Fail("no layer named \"" + text + "\" and no such file: " + c->reference_file);
  std::string ext = fs::path(c->reference_file).extension().string();
  for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (c->deviation.method == compare::Method::kC2M && ext != ".ply" && ext != ".obj")
    n.Fail("c2m compares to a mesh: PLY or OBJ, not " + c->reference_file);
}

SceneComparison ParseComparison(const Node& n, const std::set<std::string>& layer_names) {
  std::set<std::string> known = {"name", "compared", "reference", "method", "tolerance", "bins", "range"};
  for (const auto& entry : MethodKeys()) known.insert(entry.first);
  n.ExpectObject(known);
  SceneComparison c;
  c.key_json = n.raw().dump();
  for (const char* key : {"name", "compared", "reference"})
    if (!n.Has(key)) n.Fail(std::string("missing key \"") + key + "\"");
  c.name = n["name"].String();
  if (!ValidName(c.name)) n["name"].Fail("a comparison name is 1-64 characters of A-Z a-z 0-9 _ - (it names files)");
  c.compared = n["compared"].String();
  if (!layer_names.count(c.compared)) n["compared"].Fail("no layer named \"" + c.compared + "\"");
  if (n.Has("method")) c.deviation.method = Choice(n["method"], compare::ParseMethod);
  ParseReference(n["reference"], layer_names, &c);
  ParseMethodSettings(n, &c.deviation);
  if (n.Has("tolerance")) c.summary.tolerance = n["tolerance"].Number(0, 1e9);
  if (n.Has("bins")) c.summary.bins = static_cast<int>(n["bins"].Integer(1, 10000));
  if (n.Has("range")) c.summary.range = n["range"].Number(0, 1e9);
  return c;
}

// An array of named entries (views, comparisons), each parsed by `parse`; the names unique.
template <typename T, typename Parse>
std::vector<T> ParseNamedList(const Node& list, const std::string& what, Parse parse) {
  std::vector<T> entries;
  std::set<std::string> seen;
  for (size_t i = 0; i < list.ArraySize(); ++i) {
    entries.push_back(parse(list[i]));
    if (!seen.insert(entries.back().name).second)
      list[i]["name"].Fail(what + " name \"" + entries.back().name + "\" repeats");
  }
  return entries;
}

}  // namespace

std::string LayerKindName(LayerKind kind) {
  switch (kind) {
    case LayerKind::kPoints: return "points";
    case LayerKind::kFoundation: return "foundation";
    case LayerKind::kRelief: return "relief";
    case LayerKind::kPhotogrammetry: return "photogrammetry";
  }
  return "?";
}

std::vector<std::string> SceneLayer::Sources() const {
  std::vector<std::string> s;
  for (const std::string* p : {&file, &dxf, &model, &placement, &dense, &targets, &picks})
    if (!p->empty()) s.push_back(*p);
  if (!images.empty()) {
    std::vector<std::string> photos;
    std::error_code ec;
    for (fs::directory_iterator it(images, ec), end; !ec && it != end; it.increment(ec))
      if (it->is_regular_file(ec)) photos.push_back(it->path().string());
    std::sort(photos.begin(), photos.end());
    s.insert(s.end(), photos.begin(), photos.end());
  }
  for (const ReliefPanelSpec& p : panels) s.push_back(p.photo.empty() ? p.points : p.photo);
  return s;
}

FoundationPointsOptions SceneFoundationDefaults() {
  FoundationPointsOptions f;
  f.sample.density = kDefaultFoundationDensity;
  return f;
}

ImageSettings SceneRenderDefaults() {
  ImageSettings s;
  s.background = {255, 255, 255};
  return s;
}

Scene LoadScene(const std::string& path) {
  Scene scene;
  scene.path = fs::absolute(path).lexically_normal().string();
  scene.text = ReadFileToString(path);
  json j;
  try {
    j = json::parse(scene.text);
  } catch (const json::parse_error& e) {
    throw InputError(path, "byte " + std::to_string(e.byte), std::string("not valid JSON: ") + e.what());
  } catch (const json::exception& e) {  // e.g. a number beyond double's range (out_of_range)
    throw InputError(path, "", std::string("not valid JSON: ") + e.what());
  }
  const Node root(scene.path, j, "");
  root.ExpectObject({"candi_scene", "name", "origin", "seed", "crs", "render", "copc", "views", "layers",
                     "licence", "annotations", "comparisons"});
  if (!root.Has("candi_scene")) root.Fail("missing key \"candi_scene\" (the format version, 1)");
  if (root["candi_scene"].Integer(1, 1000) != 1) root["candi_scene"].Fail("this candi reads scene version 1");
  scene.name = root.Has("name") ? root["name"].String() : fs::path(path).stem().string();
  if (root.Has("origin")) {
    const Node o = root["origin"];
    if (o.raw().is_string()) {
      if (o.String() != "auto") o.Fail("expected [E, N, H] or \"auto\"");
    } else {
      scene.origin = o.Vec3();
    }
  }
  if (root.Has("seed")) scene.seed = static_cast<unsigned long long>(root["seed"].Integer(0, (1LL << 62)));
  scene.render.spbr.seed = scene.seed;
  scene.origin_json = j.value("origin", json()).dump();
  scene.render_json = j.value("render", json()).dump();
  scene.copc_json = j.value("copc", json()).dump();
  if (root.Has("crs")) scene.crs = root["crs"].Crs();
  if (root.Has("render")) {
    const Node r = root["render"];
    r.ExpectObject({"repeat_level", "width", "height", "background", "brightness"});
    ImageSettings& s = scene.render;
    if (r.Has("repeat_level"))
      s.spbr.repeat_level = static_cast<int>(r["repeat_level"].Integer(1, kMaxRepeatLevel));
    if (r.Has("width")) s.width = static_cast<int>(r["width"].Integer(1, kMaxImageSize));
    if (r.Has("height")) s.height = static_cast<int>(r["height"].Integer(1, kMaxImageSize));
    if (r.Has("background")) s.background = r["background"].Colour();
    if (r.Has("brightness")) {
      const Node b = r["brightness"];
      try {
        s.brightness = b.raw().is_number() ? Brightness::Gain(b.Number(0, Brightness::kMaxGain, true))
                                           : Brightness::Parse(b.String());
      } catch (const std::invalid_argument&) {
        b.Fail(std::string("expected ") + Brightness::Rule());
      }
    }
  }
  if (root.Has("copc")) {
    const Node c = root["copc"];
    c.ExpectObject({"layers", "scene"});
    if (c.Has("layers")) scene.copc.layers = c["layers"].Bool();
    if (c.Has("scene")) scene.copc.scene = c["scene"].Bool();
  }
  if (!root.Has("layers")) root.Fail("missing key \"layers\"");
  const Node layers = root["layers"];
  if (layers.ArraySize() == 0) layers.Fail("no layers");
  std::set<std::string> names;
  for (size_t i = 0; i < layers.ArraySize(); ++i) {
    scene.layers.push_back(ParseLayer(layers[i]));
    if (!names.insert(scene.layers.back().name).second)
      layers[i]["name"].Fail("layer name \"" + scene.layers.back().name + "\" repeats");
  }
  for (size_t i = 0; i < scene.layers.size(); ++i) {
    if (scene.layers[i].crs == "scene" && scene.crs.empty())
      layers[i]["crs"].Fail("\"scene\" needs the scene's \"crs\"");
    if (!scene.layers[i].targets_crs.empty() && scene.crs.empty())
      layers[i]["targets_crs"].Fail("needs the scene's \"crs\" (the CRS to transform the targets into)");
    for (size_t r = 0; r < scene.layers[i].replaces.size(); ++r) {
      const std::string& other = scene.layers[i].replaces[r];
      const Node at = layers[i]["replaces"][r];
      if (!names.count(other)) at.Fail("no layer named \"" + other + "\"");
      if (other == scene.layers[i].name) at.Fail("a layer cannot replace itself");
    }
  }
  if (root.Has("views")) {
    scene.views = ParseNamedList<SceneView>(root["views"], "view",
                                            [&](const Node& n) { return ParseSceneView(n, names); });
  }
  if (root.Has("licence")) scene.licence = root["licence"].String();
  if (root.Has("annotations")) {
    const Node list = root["annotations"];
    for (size_t i = 0; i < list.ArraySize(); ++i) {
      const Node n = list[i];
      n.ExpectObject({"title", "text", "position", "view"});
      SceneAnnotation a;
      if (!n.Has("title")) n.Fail("missing key \"title\"");
      a.title = n["title"].String();
      if (a.title.empty() || a.title.size() > 200) n["title"].Fail("a title is 1-200 characters");
      if (n.Has("text")) a.text = n["text"].String();
      if (!n.Has("position")) n.Fail("missing key \"position\" ([E, N, H], world)");
      a.position = n["position"].Vec3();
      if (n.Has("view")) {
        const Node v = n["view"];
        if (v.raw().is_string()) {
          a.view = v.String();
          const bool known = std::any_of(scene.views.begin(), scene.views.end(),
                                         [&](const SceneView& sv) { return sv.name == a.view; });
          if (!known) v.Fail("no view named \"" + a.view + "\"");
        } else if (v.raw().is_object()) {
          a.camera = InlineCamera(v, scene.path);
        } else {
          v.Fail("expected a view's name or an inline camera object");
        }
      }
      scene.annotations.push_back(a);
    }
  }
  if (root.Has("comparisons")) {
    scene.comparisons = ParseNamedList<SceneComparison>(root["comparisons"], "comparison",
                                                        [&](const Node& n) { return ParseComparison(n, names); });
  }
  return scene;
}

double ViewOpacity(const SceneView& view, const SceneLayer& layer) {
  double a = layer.opacity;
  if (view.focus) a = layer.highlight ? view.focus_opacity : layer.opacity * view.dim;
  const auto it = view.opacity.find(layer.name);
  if (it != view.opacity.end()) a = it->second;
  return a;
}

}  // namespace candi::pipeline
