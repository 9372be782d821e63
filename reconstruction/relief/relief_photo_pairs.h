// Real-photo pairs for the relief network: a photograph, the depth of the scene in that camera
// and a mask of where the depth is known, from a photogrammetric reconstruction (COLMAP cameras
// and poses, a dense cloud in the same frame, e.g. OpenMVS's or `candi dense`'s).
//
// Depth: every cloud point is projected with the camera model, distortion included, exactly as
// COLMAP does (colmap_model.h), so the pair lines up with the original, distorted photo. A pixel
// keeps the nearest point (a z-buffer). A point that a nearer one within `occlusion_radius`
// pixels hides by more than `occlusion_tolerance` of its depth is dropped: at a sparse spot of
// the front surface, points of the surface behind would otherwise show through. This also masks
// a band of up to `occlusion_radius` pixels on the far side of every depth edge (no data there,
// never a wrong depth). Pixels without a point are masked.
//
// Levels: a photograph has no front plane, so the camera depth z (model units along the optical
// axis) is mapped per photo: near = the `near_percentile` of the known depths -> level 1
// (kMinValidLevel), far = the `far_percentile` -> level 255, linear between and clamped. Both
// are recorded (PNG text candi_depth_near / candi_depth_far) so that a level converts back:
// z = near + (level - 1) * (far - near) / 254. A view whose known depths span less than 1e-9 of
// their magnitude (a wall seen square-on and nothing else) gets level 128 everywhere known.
//
// Files (WritePhotoPair / ReadPhotoPairs, the format `relief eval --pairs` scores and users may
// bring): DIR/<stem>_photo.png (8-bit grey), <stem>_depth.png (16-bit levels * 256, 0 = no data)
// and optionally <stem>_mask.png (8-bit, 0 = no data); all three the same size.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::relief {

struct PhotoPairOptions {
  int max_side = 512;                 // longer side of the pair, pixels, [32, 16384]
  int occlusion_radius = 1;           // pixels, [0, 16]
  double occlusion_tolerance = 0.03;  // fraction of the depth, [0, 1]
  double near_percentile = 0.02;      // of the known depths -> level 1, [0, 1)
  double far_percentile = 0.98;       // -> level 255, (near_percentile, 1]
  void Check() const;                 // throws std::invalid_argument naming the field
};

struct PhotoPair {
  std::string name;  // stem of the files (the image name without folders and extension)
  ImageF photo;      // grey [0, 1]
  ImageF depth;      // levels; 0 where the mask is 0
  Image8 mask;       // 255 where the depth is known
  double near = 0, far = 0;  // camera depth of level 1 and level 255 (model units)
  // 255 where the pixel's nearest point lies in a held-out region (BuildPhotoPair's in_region;
  // empty without one). Not written by WritePhotoPair.
  Image8 region;
};

// A part of the scene held out of training: a surface the network must never see, scored
// afterwards as an unseen one. The points inside an axis-aligned box, or on the positive side of
// a plane (normal . p > offset), in the cloud's frame (the COLMAP model's). Text forms:
// "box:x0,y0,z0,x1,y1,z1" and "side:nx,ny,nz,offset"; ParseSceneRegion throws
// std::invalid_argument quoting the text for anything else (an empty box, a zero normal, NaN).
struct SceneRegion {
  enum class Kind { kBox, kSide };
  Kind kind = Kind::kBox;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // box
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();                            // side
  double offset = 0;
  bool Contains(const Eigen::Vector3d& p) const {
    return kind == Kind::kBox ? (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all()
                              : normal.dot(p) > offset;
  }
};
SceneRegion ParseSceneRegion(const std::string& text);

// Level of camera depth z in a pair with this near/far, and back (see above).
double LevelOfCameraDepth(double z, double near, double far);
double CameraDepthOfLevel(double level, double near, double far);

// The pair of one registered image. `photo` is the photograph at any resolution with the
// camera's aspect ratio (e.g. the originals of a model computed on downscaled copies); `points`
// are in the model frame (non-finite ones are skipped). The pair is the camera's size scaled so
// that its longer side is at most max_side. Throws InputError(photo_path) when the photo's aspect
// differs from the camera's by more than 1 %, std::invalid_argument for an unsupported camera
// model.
// in_region (optional, one flag a point): pair.region marks the pixels whose nearest point is
// flagged (also where the occlusion test then drops it).
PhotoPair BuildPhotoPair(const PhotoPairOptions& options, const photogrammetry::ColmapCamera& camera,
                         const photogrammetry::ColmapImage& image, const ImageF& photo,
                         const std::string& photo_path, const std::vector<Eigen::Vector3d>& points,
                         const std::vector<uint8_t>* in_region = nullptr);

// Writes the three files of a pair into dir (created if missing), each atomically.
void WritePhotoPair(const std::string& dir, const PhotoPair& pair);
// Every <stem>_photo.png of dir with its <stem>_depth.png (and <stem>_mask.png when present), in
// name order; near/far from the depth's text (0 when absent). Throws InputError naming the file
// for a missing depth, sizes that differ, or a folder without pairs.
std::vector<PhotoPair> ReadPhotoPairs(const std::string& dir);

}  // namespace candi::relief
