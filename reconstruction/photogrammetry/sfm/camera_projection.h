// COLMAP 3.8's camera models, from a normalised image point (x/z, y/z) to pixels, as one template
// over the scalar: ProjectToImage evaluates it in doubles and the joint adjustment's residuals in
// Ceres's jets, so both use the same formula. Parameters are in COLMAP's order for the model.
#pragma once

#include <string>

namespace candi::photogrammetry {

enum class ProjectionModel { kSimplePinhole, kPinhole, kSimpleRadial, kRadial, kOpenCv, kFullOpenCv, kUnsupported };

inline ProjectionModel ProjectionModelOf(const std::string& name) {
  if (name == "SIMPLE_PINHOLE") return ProjectionModel::kSimplePinhole;
  if (name == "PINHOLE") return ProjectionModel::kPinhole;
  if (name == "SIMPLE_RADIAL") return ProjectionModel::kSimpleRadial;
  if (name == "RADIAL") return ProjectionModel::kRadial;
  if (name == "OPENCV") return ProjectionModel::kOpenCv;
  if (name == "FULL_OPENCV") return ProjectionModel::kFullOpenCv;
  return ProjectionModel::kUnsupported;
}

// (u, v) = (x/z, y/z) of the point in the camera's frame; `p` holds the model's parameters (doubles,
// or jets where they are adjusted too). Returns false (and leaves the pixel alone) for kUnsupported.
template <typename T, typename P>
bool PixelFromNormalized(ProjectionModel model, const P* p, const T& u, const T& v, T* px, T* py) {
  const T u2 = u * u, v2 = v * v, uv = u * v, r2 = u2 + v2;
  switch (model) {
    case ProjectionModel::kSimplePinhole:
      *px = p[0] * u + p[1], *py = p[0] * v + p[2];
      return true;
    case ProjectionModel::kPinhole:
      *px = p[0] * u + p[2], *py = p[1] * v + p[3];
      return true;
    case ProjectionModel::kSimpleRadial:
    case ProjectionModel::kRadial: {
      const T radial = model == ProjectionModel::kRadial ? p[3] * r2 + p[4] * r2 * r2 : p[3] * r2;
      *px = p[0] * (u + u * radial) + p[1], *py = p[0] * (v + v * radial) + p[2];
      return true;
    }
    case ProjectionModel::kOpenCv: {
      const T radial = p[4] * r2 + p[5] * r2 * r2;
      const T du = u * radial + 2.0 * p[6] * uv + p[7] * (r2 + 2.0 * u2);
      const T dv = v * radial + 2.0 * p[7] * uv + p[6] * (r2 + 2.0 * v2);
      *px = p[0] * (u + du) + p[2], *py = p[1] * (v + dv) + p[3];
      return true;
    }
    case ProjectionModel::kFullOpenCv: {
      const T r4 = r2 * r2, r6 = r4 * r2;
      const T radial = (1.0 + p[4] * r2 + p[5] * r4 + p[8] * r6) / (1.0 + p[9] * r2 + p[10] * r4 + p[11] * r6);
      const T du = u * radial + 2.0 * p[6] * uv + p[7] * (r2 + 2.0 * u2) - u;
      const T dv = v * radial + 2.0 * p[7] * uv + p[6] * (r2 + 2.0 * v2) - v;
      *px = p[0] * (u + du) + p[2], *py = p[1] * (v + dv) + p[3];
      return true;
    }
    case ProjectionModel::kUnsupported: break;
  }
  return false;
}

// The model's parameter count, and where its principal point is (cx at that index, cy after it);
// 0 for kUnsupported.
inline int ProjectionParams(ProjectionModel model) {
  switch (model) {
    case ProjectionModel::kSimplePinhole: return 3;
    case ProjectionModel::kPinhole: case ProjectionModel::kSimpleRadial: return 4;
    case ProjectionModel::kRadial: return 5;
    case ProjectionModel::kOpenCv: return 8;
    case ProjectionModel::kFullOpenCv: return 12;
    case ProjectionModel::kUnsupported: break;
  }
  return 0;
}
inline int PrincipalPointIndex(ProjectionModel model) {
  return model == ProjectionModel::kPinhole || model == ProjectionModel::kOpenCv ||
                 model == ProjectionModel::kFullOpenCv
             ? 2
             : 1;
}

}  // namespace candi::photogrammetry
