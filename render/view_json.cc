#include "render/view_json.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/check.h"

namespace candi::render {

namespace {

using nlohmann::json;

[[noreturn]] void Bad(const std::string& path, const std::string& where, const std::string& what) {
  throw InputError(path, where, what);
}

Eigen::Vector3d Vec3(const std::string& path, const json& j, const std::string& key) {
  const std::string where = "/" + key;
  if (!j.is_array() || j.size() != 3) Bad(path, where, "expected an array of three numbers");
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) {
    if (!j[k].is_number()) Bad(path, where + "/" + std::to_string(k), "expected a number");
    v[k] = j[k].get<double>();
    if (!std::isfinite(v[k])) Bad(path, where + "/" + std::to_string(k), "not a finite number");
  }
  return v;
}

double Number(const std::string& path, const json& j, const std::string& key) {
  if (!j.is_number()) Bad(path, "/" + key, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) Bad(path, "/" + key, "not a finite number");
  return v;
}

int Integer(const std::string& path, const json& j, const std::string& key) {
  if (!j.is_number_integer()) Bad(path, "/" + key, "expected an integer");
  const bool fits = j.is_number_unsigned() ? j.get<uint64_t>() <= static_cast<uint64_t>(std::numeric_limits<int>::max())
                                           : j.get<int64_t>() >= std::numeric_limits<int>::min() &&
                                                 j.get<int64_t>() <= std::numeric_limits<int>::max();
  if (!fits) Bad(path, "/" + key, "out of range: " + j.dump());
  return j.get<int>();
}

// A page's "settings" (see the header).
void ParseSettings(const std::string& path, const json& j, SavedViewSettings* out) {
  if (!j.is_object()) Bad(path, "/settings", "expected an object");
  SavedViewSettings s;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    const std::string where = "/settings/" + k;
    if (k == "layers") {
      if (!v.is_array()) Bad(path, where, "expected an array of shares");
      for (size_t i = 0; i < v.size(); ++i) {
        const double f = Number(path, v[i], "settings/layers/" + std::to_string(i));
        if (f < 0 || f > 16) Bad(path, where + "/" + std::to_string(i), "a share must be in [0, 16]");
        s.layer_shares.push_back(f);
      }
    } else if (k == "layer_names") {
      if (!v.is_array()) Bad(path, where, "expected an array of names");
      for (size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_string()) Bad(path, where + "/" + std::to_string(i), "expected a string");
        s.layer_names.push_back(v[i].get<std::string>());
      }
    } else if (k == "clip") {
      if (!v.is_array()) Bad(path, where, "expected an array of [px, py, pz, nx, ny, nz]");
      for (size_t i = 0; i < v.size(); ++i) {
        const std::string at = "settings/clip/" + std::to_string(i);
        if (!v[i].is_array() || v[i].size() != 6) Bad(path, "/" + at, "expected [px, py, pz, nx, ny, nz]");
        ClipPlane plane;
        for (int a = 0; a < 3; ++a) {
          plane.point[a] = Number(path, v[i][a], at + "/" + std::to_string(a));
          plane.normal[a] = Number(path, v[i][3 + a], at + "/" + std::to_string(3 + a));
        }
        s.clip.planes.push_back(plane);
      }
      try {
        s.clip.Check(path + where);
      } catch (const std::invalid_argument& e) {
        Bad(path, where, e.what());
      }
    } else if (k != "repeat_level" && k != "seed" && k != "opaque" && k != "point_size" && k != "background" &&
               k != "brightness") {
      Bad(path, where, "unknown key (known: layers layer_names clip repeat_level seed opaque point_size background "
                       "brightness)");
    }
  }
  if (s.layer_shares.size() != s.layer_names.size()) {
    Bad(path, "/settings/layers", "gives " + std::to_string(s.layer_shares.size()) + " shares for " +
                                      std::to_string(s.layer_names.size()) + " layer_names");
  }
  if (out) *out = s;
}

}  // namespace

Camera ParseView(const std::string& text, const std::string& path, SavedViewSettings* settings) {
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    Bad(path, "byte " + std::to_string(e.byte), std::string("not valid JSON: ") + e.what());
  } catch (const json::exception& e) {  // e.g. a number beyond double's range (out_of_range)
    Bad(path, "", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) Bad(path, "/", "expected a JSON object");
  Camera c;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    if (k == "projection") {
      if (v == "perspective") c.projection = Projection::kPerspective;
      else if (v == "orthographic") c.projection = Projection::kOrthographic;
      else Bad(path, "/projection", "expected \"perspective\" or \"orthographic\"");
    } else if (k == "width") c.width = Integer(path, v, k);
    else if (k == "height") c.height = Integer(path, v, k);
    else if (k == "eye") c.eye = Vec3(path, v, k);
    else if (k == "target") c.target = Vec3(path, v, k);
    else if (k == "up") c.up = Vec3(path, v, k);
    else if (k == "fov_y_deg") c.fov_y_deg = Number(path, v, k);
    else if (k == "ortho_height") c.ortho_height = Number(path, v, k);
    else if (k == "near") c.near = Number(path, v, k);
    else if (k == "settings") ParseSettings(path, v, settings);
    else Bad(path, "/" + k, "unknown key (known: projection width height eye target up fov_y_deg ortho_height near "
                            "settings)");
  }
  try {
    c.Check();
  } catch (const std::invalid_argument& e) {
    Bad(path, "", e.what());
  }
  return c;
}

std::string ViewToJson(const Camera& c) {
  json j;
  j["projection"] = c.projection == Projection::kPerspective ? "perspective" : "orthographic";
  j["width"] = c.width;
  j["height"] = c.height;
  j["eye"] = {c.eye.x(), c.eye.y(), c.eye.z()};
  j["target"] = {c.target.x(), c.target.y(), c.target.z()};
  j["up"] = {c.up.x(), c.up.y(), c.up.z()};
  j["fov_y_deg"] = c.fov_y_deg;
  j["ortho_height"] = c.ortho_height;
  j["near"] = c.near;
  return j.dump(2);
}

Camera LoadView(const std::string& path, SavedViewSettings* settings) {
  return ParseView(ReadFileToString(path), path, settings);
}

void SaveView(const std::string& path, const Camera& c) { WriteFileAtomic(path, ViewToJson(c) + "\n"); }

}  // namespace candi::render
