// The viewer's message protocol (WebSocket, one JSON text message each way per event).
//
// Page -> server (every message is checked; anything else closes the socket with a policy error):
//   {"type": "view", "seq": 7,                 the page's whole state; the latest one wins
//    "camera": {...},                          render/view_json.h's format (world coordinates)
//    "settings": {"repeat_level": 100,         L, [1, 10000]
//                 "point_size": 1,             pixels, [1, 64]
//                 "background": [r, g, b],     0..255 each
//                 "brightness": "auto" | "none" | gain (0, 100],
//                 "opaque": false,             true: L = 1
//                 "seed": 1,                   [0, 2^53]
//                 "layers": [1, 0.5, 0]}}      per archive layer, the share of its points drawn,
//                                              [0, 16] (0 hides it; opacity follows the point-number
//                                              law, alpha' = 1 - (1 - alpha)^f); absent: all 1
//   {"type": "pick", "seq": 8, "x": 512.5, "y": 300}   the nearest drawn point under a pixel of
//                                              the last view (fly to a double-clicked point)
// Server -> page:
//   binary frames: a 4-byte little-endian header length, the header (JSON: seq, ensembles,
//   repeat_level, format "jpeg" | "png", width, height, gain, render_ms, converged), then the
//   image file; the converged frame is PNG (lossless), the others JPEG.
//   {"type": "pick", "seq": 8, "hit": true, "point": [x, y, z] (world), "depth": d}
//   {"type": "error", "message": "..."}
// Limits: a message is at most kMaxMessageBytes; images at most kMaxImageSide pixels a side.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "render/camera.h"

namespace candi::view {

inline constexpr size_t kMaxMessageBytes = 16384;
inline constexpr int kMaxImageSide = 4096;
inline constexpr int kMaxRepeatLevel = 10000;
inline constexpr size_t kMaxLayers = 1024;

// What the page sets besides the camera.
struct ViewSettings {
  int repeat_level = 100;
  double point_size = 1.0;
  Rgb8 background{0, 0, 0};  // candi render's default; a build's scene sets its own
  double brightness = -1;  // -1: auto; otherwise the gain (1: none)
  bool opaque = false;
  uint64_t seed = 1;
  std::vector<double> layer_fraction;  // per archive layer; empty: all 1
  // L as drawn: 1 when opaque.
  int EffectiveRepeatLevel() const { return opaque ? 1 : repeat_level; }
  bool operator==(const ViewSettings& o) const {
    return repeat_level == o.repeat_level && point_size == o.point_size && background == o.background &&
           brightness == o.brightness && opaque == o.opaque && seed == o.seed && layer_fraction == o.layer_fraction;
  }
};

// One image to converge to: the camera (world frame) and the settings.
struct ViewState {
  render::Camera camera;
  ViewSettings settings;
};
bool SameImage(const ViewState& a, const ViewState& b);

enum class MessageType { kView, kPick };

struct ClientMessage {
  MessageType type = MessageType::kView;
  uint64_t seq = 0;
  ViewState view;           // kView
  double x = 0, y = 0;      // kPick: pixel (continuous coordinates of the last view)
};

// Parses and checks one message. Throws std::invalid_argument naming the JSON path of the
// culprit (e.g. "/camera/eye/1: not a finite number") for anything malformed or out of range.
ClientMessage ParseClientMessage(const std::string& text);

// The header of a binary frame message.
struct FrameHeader {
  uint64_t seq = 0;
  int ensembles = 0, repeat_level = 0;
  bool png = false;
  int width = 0, height = 0;
  double gain = 1, render_ms = 0;
};
std::string FrameMessage(const FrameHeader& header, const std::string& image);

std::string PickReply(uint64_t seq, bool hit, const Eigen::Vector3d& world_point, double depth);
std::string ErrorReply(const std::string& message);

}  // namespace candi::view
