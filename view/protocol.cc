#include "view/protocol.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "core/check.h"
#include "render/view_json.h"

namespace candi::view {

namespace {

using nlohmann::json;

[[noreturn]] void Bad(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

double Number(const json& j, const std::string& where, double lo, double hi) {
  if (!j.is_number()) Bad(where, "expected a number");
  const double v = j.get<double>();
  if (!std::isfinite(v)) Bad(where, "not a finite number");
  if (v < lo || v > hi) Bad(where, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return v;
}

uint64_t Whole(const json& j, const std::string& where, uint64_t hi) {
  if (!j.is_number_unsigned()) Bad(where, "expected a whole number >= 0");
  const uint64_t v = j.get<uint64_t>();
  if (v > hi) Bad(where, "out of range (at most " + std::to_string(hi) + ")");
  return v;
}

ViewSettings ParseSettings(const json& j) {
  if (!j.is_object()) Bad("/settings", "expected an object");
  ViewSettings s;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    const std::string where = "/settings/" + k;
    if (k == "repeat_level") {
      s.spbr.repeat_level = static_cast<int>(Whole(v, where, kMaxViewRepeatLevel));
      if (s.spbr.repeat_level < 1) Bad(where, "must be >= 1");
    } else if (k == "point_size") {
      s.spbr.point_size = Number(v, where, 1, 64);
    } else if (k == "background") {
      if (!v.is_array() || v.size() != 3) Bad(where, "expected [r, g, b]");
      uint8_t c[3];
      for (int i = 0; i < 3; ++i) c[i] = static_cast<uint8_t>(Whole(v[i], where + "/" + std::to_string(i), 255));
      s.background = {c[0], c[1], c[2]};
    } else if (k == "brightness") {
      if (v == "auto" || v == "none") {
        s.brightness = Brightness::Parse(v.get<std::string>());
      } else if (v.is_number()) {
        const double gain = Number(v, where, 0, Brightness::kMaxGain);
        if (!(gain > 0)) Bad(where, "a gain must be > 0");
        s.brightness = Brightness::Gain(gain);
      } else {
        Bad(where, std::string("expected ") + Brightness::Rule());
      }
    } else if (k == "opaque") {
      if (!v.is_boolean()) Bad(where, "expected true or false");
      s.spbr.opaque = v.get<bool>();
    } else if (k == "seed") {
      s.spbr.seed = Whole(v, where, uint64_t{1} << 53);
    } else if (k == "layers") {
      if (!v.is_array() || v.size() > kMaxLayers) Bad(where, "expected an array of at most 1024 numbers");
      for (size_t i = 0; i < v.size(); ++i) s.layer_fraction.push_back(Number(v[i], where + "/" + std::to_string(i), 0, 16));
    } else if (k == "clip") {
      if (!v.is_array() || v.size() > kMaxClipPlanes) Bad(where, "expected an array of at most 16 planes");
      for (size_t i = 0; i < v.size(); ++i) {
        const std::string w = where + "/" + std::to_string(i);
        if (!v[i].is_array() || v[i].size() != 6) Bad(w, "expected [px, py, pz, nx, ny, nz]");
        double x[6];
        for (int c = 0; c < 6; ++c) x[c] = Number(v[i][c], w + "/" + std::to_string(c), -1e9, 1e9);
        const Eigen::Vector3d n(x[3], x[4], x[5]);
        if (!(n.norm() > 1e-12)) Bad(w, "the normal is zero");
        s.clip.planes.push_back({Eigen::Vector3d(x[0], x[1], x[2]), n});
      }
    } else {
      Bad(where, "unknown key (known: repeat_level point_size background brightness opaque seed layers clip)");
    }
  }
  return s;
}

}  // namespace

bool SameImage(const ViewState& a, const ViewState& b) {
  const render::Camera &x = a.camera, &y = b.camera;
  return a.settings == b.settings && x.projection == y.projection && x.width == y.width && x.height == y.height &&
         x.eye == y.eye && x.target == y.target && x.up == y.up && x.fov_y_deg == y.fov_y_deg &&
         x.ortho_height == y.ortho_height && x.near == y.near;
}

ClientMessage ParseClientMessage(const std::string& text) {
  if (text.size() > kMaxMessageBytes) {
    Bad("/", "message of " + std::to_string(text.size()) + " bytes (at most " + std::to_string(kMaxMessageBytes) + ")");
  }
  json j;
  try {
    j = json::parse(text);
  } catch (const json::parse_error& e) {
    Bad("byte " + std::to_string(e.byte), "not valid JSON");
  } catch (const json::exception& e) {
    Bad("/", std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) Bad("/", "expected a JSON object");
  const auto type = j.find("type");
  if (type == j.end() || !type->is_string()) Bad("/type", "expected \"view\", \"pick\" or \"section\"");
  ClientMessage m;
  const std::string t = type->get<std::string>();
  if (t == "view") m.type = MessageType::kView;
  else if (t == "pick") m.type = MessageType::kPick;
  else if (t == "section") m.type = MessageType::kSection;
  else Bad("/type", "unknown message type (known: view pick section)");
  bool has_camera = false, has_plane = false;
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    const json& v = it.value();
    if (k == "type") continue;
    if (k == "seq") {
      m.seq = Whole(v, "/seq", uint64_t{1} << 53);
    } else if (m.type == MessageType::kView && k == "camera") {
      if (!v.is_object()) Bad("/camera", "expected an object");
      try {
        m.view.camera = render::ParseView(v.dump(), "message");
      } catch (const InputError& e) {
        Bad("/camera", e.what());
      }
      has_camera = true;
    } else if (m.type == MessageType::kView && k == "settings") {
      m.view.settings = ParseSettings(v);
    } else if (m.type == MessageType::kPick && (k == "x" || k == "y")) {
      (k == "x" ? m.x : m.y) = Number(v, "/" + k, -1e6, 1e6);
    } else if (m.type == MessageType::kSection && (k == "point" || k == "normal")) {
      if (!v.is_array() || v.size() != 3) Bad("/" + k, "expected [x, y, z]");
      Eigen::Vector3d x;
      for (int c = 0; c < 3; ++c) x[c] = Number(v[c], "/" + k + "/" + std::to_string(c), -1e9, 1e9);
      (k == "point" ? m.section.point : m.section.normal) = x;
      has_plane |= k == "normal";
    } else if (m.type == MessageType::kSection && k == "thickness") {
      m.section.thickness = Number(v, "/thickness", 0, 1e4);
      if (!(m.section.thickness > 0)) Bad("/thickness", "must be > 0 m");
    } else {
      Bad("/" + k, "unknown key for a " + t + " message");
    }
  }
  if (m.type == MessageType::kSection) {
    if (!has_plane) Bad("/normal", "missing");
    if (!(m.section.normal.norm() > 1e-12)) Bad("/normal", "the normal is zero");
  }
  if (m.type == MessageType::kView) {
    if (!has_camera) Bad("/camera", "missing");
    const render::Camera& c = m.view.camera;
    if (c.width > kMaxImageSide || c.height > kMaxImageSide) {
      Bad("/camera", std::to_string(c.width) + "x" + std::to_string(c.height) + " pixels (at most " +
                         std::to_string(kMaxImageSide) + " a side)");
    }
    // Eye and target far apart compared with their magnitude, so the view direction survives
    // float rendering; Camera::Check has rejected coincident ones.
    const double scale = std::max(c.eye.norm(), c.target.norm());
    if (!((c.target - c.eye).norm() > 1e-9 * scale)) Bad("/camera", "eye and target (nearly) coincide");
    if (!(std::isfinite(scale) && scale < 1e9)) Bad("/camera", "coordinates beyond 1e9 m");
  }
  return m;
}

std::string FrameMessage(const FrameHeader& h, const std::string& image) {
  const std::string header = json{{"seq", h.seq},
                                  {"ensembles", h.ensembles},
                                  {"repeat_level", h.repeat_level},
                                  {"format", h.png ? "png" : "jpeg"},
                                  {"width", h.width},
                                  {"height", h.height},
                                  {"gain", h.gain},
                                  {"render_ms", h.render_ms},
                                  {"converged", h.ensembles == h.repeat_level},
                                  {"sample", h.sample}}
                                 .dump();
  std::string out(4, '\0');
  const uint32_t n = static_cast<uint32_t>(header.size());
  for (int i = 0; i < 4; ++i) out[i] = static_cast<char>((n >> (8 * i)) & 0xff);
  out += header;
  out += image;
  return out;
}

std::string PickReply(uint64_t seq, const std::vector<PickHitWorld>& hits) {
  json j = {{"type", "pick"}, {"seq", seq}, {"hit", !hits.empty()}};
  if (!hits.empty()) {
    j["point"] = {hits[0].world.x(), hits[0].world.y(), hits[0].world.z()};
    j["depth"] = hits[0].depth;
    j["layer"] = hits[0].layer;
    json all = json::array();
    for (const PickHitWorld& h : hits) {
      json hit = {{"layer", h.layer}, {"point", {h.world.x(), h.world.y(), h.world.z()}}, {"depth", h.depth}};
      if (h.field) {
        hit["value"] = h.value ? json(*h.value) : json(nullptr);
        hit["value_half_width"] = h.value_half_width;
      }
      all.push_back(hit);
    }
    j["hits"] = all;
  }
  return j.dump();
}

std::string ErrorReply(const std::string& message) {
  // Replace invalid UTF-8 (a message may quote what the page sent).
  return json{{"type", "error"}, {"message", message}}.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace candi::view
