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
//                 "layers": [1, 0.5, 0],       per archive layer, the share of its points drawn,
//                                              [0, 16] (0 hides it; opacity follows the point-number
//                                              law, alpha' = 1 - (1 - alpha)^f); absent: all 1
//                 "clip": [[px, py, pz, nx, ny, nz], ...]}}   at most kMaxClipPlanes half-spaces
//                                              (world; each keeps the side its normal points into):
//                                              a clip box is six, a section slab two
//   {"type": "pick", "seq": 8, "x": 512.5, "y": 300}   the drawn points under a pixel of the last
//                                              view: only shown ones (not hidden layers, not clipped
//                                              away, only the share of a layer that is drawn)
//   {"type": "section", "seq": 9, "point": [x, y, z], "normal": [x, y, z], "thickness": t}
//                                              the section lines of that slab (the last view's layers
//                                              and clipping), as candi section writes them
// Server -> page:
//   binary frames: a 4-byte little-endian header length, the header (JSON: seq, ensembles,
//   repeat_level, format "jpeg" | "png", width, height, gain, render_ms, converged, sample), then
//   the image file; the converged frame is PNG (lossless), the others JPEG. sample < 1: a preview
//   of that random share of the first ensemble's points (ensembles 0), when one whole ensemble
//   would take long.
//   {"type": "pick", "seq": 8, "hit": true, "point": [x, y, z] (world), "depth": d, "layer": i,
//    "hits": [{"layer": i, "point": [...], "depth": d}, ...]}   the nearest point of each layer
//                                              under the pixel, nearest first ("point": the first)
//   {"type": "section", "seq": 9, ...}         what the section exporter returns (dxf, svg, csv text
//                                              and a summary), or {"type": "error", ...}
//   {"type": "error", "message": "..."}
// Limits: a message is at most kMaxMessageBytes; images at most kMaxImageSide pixels a side.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/clip.h"
#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "render/camera.h"

namespace candi::view {

inline constexpr size_t kMaxMessageBytes = 16384;
inline constexpr int kMaxImageSide = 4096;
inline constexpr int kMaxViewRepeatLevel = 10000;  // a page's L (the server draws every ensemble)
inline constexpr size_t kMaxLayers = 1024;
inline constexpr size_t kMaxClipPlanes = 16;

inline bool SameClip(const ClipRegion& a, const ClipRegion& b) {
  if (a.planes.size() != b.planes.size()) return false;
  for (size_t i = 0; i < a.planes.size(); ++i) {
    if (a.planes[i].point != b.planes[i].point || a.planes[i].normal != b.planes[i].normal) return false;
  }
  return true;
}


// What the page sets besides the camera.
struct ViewSettings {
  SpbrSettings spbr;         // L in [1, kMaxViewRepeatLevel], seed in [0, 2^53], point size, opaque
  Rgb8 background{0, 0, 0};  // candi render's default; a build's record sets its own
  Brightness brightness;
  std::vector<double> layer_fraction;  // per archive layer; empty: all 1
  ClipRegion clip;                     // world frame; empty: nothing clipped
  bool operator==(const ViewSettings& o) const {
    return spbr == o.spbr && background == o.background && brightness == o.brightness &&
           layer_fraction == o.layer_fraction && SameClip(clip, o.clip);
  }
};

// One image to converge to: the camera (world frame) and the settings.
struct ViewState {
  render::Camera camera;
  ViewSettings settings;
};
bool SameImage(const ViewState& a, const ViewState& b);

enum class MessageType { kView, kPick, kSection };

// A section of the slab |(x - point) . n| <= thickness / 2 (world), n = normal / |normal|.
struct SectionRequest {
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitY();
  double thickness = 0.1;   // m, (0, 1e4]
};

struct ClientMessage {
  MessageType type = MessageType::kView;
  uint64_t seq = 0;
  ViewState view;           // kView
  double x = 0, y = 0;      // kPick: pixel (continuous coordinates of the last view)
  SectionRequest section;   // kSection
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
  double sample = 1;  // < 1: a preview of a share of one ensemble's points (ensembles 0)
};
std::string FrameMessage(const FrameHeader& header, const std::string& image);

struct PickHitWorld {
  int layer = 0;
  Eigen::Vector3d world = Eigen::Vector3d::Zero();
  double depth = 0;
  // Points coloured by a field: its value, read back from the point's colour (none: grey,
  // outside the range or undefined), and how far the values of that colour reach either side.
  bool field = false;
  std::optional<double> value;
  double value_half_width = 0;
};
// `hits`: nearest first; empty: no hit.
std::string PickReply(uint64_t seq, const std::vector<PickHitWorld>& hits);
std::string ErrorReply(const std::string& message);

}  // namespace candi::view
