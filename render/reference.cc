#include "render/reference.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "render/frame.h"
#include "render/splat_cloud.h"

namespace candi::render {

void ReferenceOptions::Check() const { spbr.Check(); }

namespace {

struct Fragment {
  uint32_t pixel;
  uint64_t key;  // depth and colour, as SPBR packs them
  float alpha;
  float depth;
};

std::vector<Fragment> Fragments(const ReferenceOptions& options, const Camera& camera,
                                const LocalFrame& frame, const std::vector<const PointCloud*>& clouds) {
  options.Check();
  const Camera::Projector p = camera.MakeProjector();
  std::vector<Fragment> out;
  for (const PointCloud* c : clouds) {
    const Eigen::Vector3d shift = c->frame.origin - frame.origin;
    const ScalarField* m = options.use_multiplicity && !options.spbr.opaque
                               ? c->FindScalar(kMultiplicityField)
                               : nullptr;
    for (size_t i = 0; i < c->size(); ++i) {
      const double copies =
          m ? std::clamp(std::round(m->Get(i)), 0.0, double(options.spbr.EffectiveRepeatLevel()))
            : 1.0;
      double u, v, depth;
      if (copies <= 0 || !p.Project(c->positions[i] + shift, &u, &v, &depth)) continue;
      if (!(u >= 0 && u < camera.width && v >= 0 && v < camera.height)) continue;
      const uint32_t pixel = static_cast<uint32_t>(std::floor(v)) * camera.width +
                             static_cast<uint32_t>(std::floor(u));
      const Rgb8 color = c->schema.colors ? c->colors[i] : options.default_color;
      out.push_back({pixel, PackKey(static_cast<float>(depth), color),
                     static_cast<float>(copies / options.spbr.EffectiveRepeatLevel()),
                     static_cast<float>(depth)});
    }
  }
  return out;
}

inline void Unpack(uint64_t key, double rgb[3]) {
  rgb[0] = (key >> 16) & 0xff;
  rgb[1] = (key >> 8) & 0xff;
  rgb[2] = key & 0xff;
}

}  // namespace

ImageF RenderSortedBlend(const ReferenceOptions& options, const Camera& camera,
                         const LocalFrame& frame, const std::vector<const PointCloud*>& clouds) {
  std::vector<Fragment> f = Fragments(options, camera, frame, clouds);
  std::sort(f.begin(), f.end(), [](const Fragment& a, const Fragment& b) {
    return a.pixel != b.pixel ? a.pixel < b.pixel : a.key < b.key;
  });
  ImageF image(camera.width, camera.height, 3);
  const double bg[3] = {double(options.background.r), double(options.background.g), double(options.background.b)};
  std::vector<double> transmit(static_cast<size_t>(camera.width) * camera.height, 1.0);
  std::vector<double> color(3 * transmit.size(), 0.0);
  for (const Fragment& g : f) {
    double rgb[3];
    Unpack(g.key, rgb);
    double& t = transmit[g.pixel];
    for (int c = 0; c < 3; ++c) color[3 * g.pixel + c] += t * g.alpha * rgb[c];
    t *= 1.0 - g.alpha;
  }
  for (size_t p = 0; p < transmit.size(); ++p) {
    for (int c = 0; c < 3; ++c) image.data()[3 * p + c] = static_cast<float>(color[3 * p + c] + transmit[p] * bg[c]);
  }
  return image;
}

ImageF RenderWeightedOit(const ReferenceOptions& options, const Camera& camera,
                         const LocalFrame& frame, const std::vector<const PointCloud*>& clouds) {
  const std::vector<Fragment> f = Fragments(options, camera, frame, clouds);
  float zmin = std::numeric_limits<float>::max(), zmax = -zmin;
  for (const Fragment& g : f) zmin = std::min(zmin, g.depth), zmax = std::max(zmax, g.depth);
  const size_t pixels = static_cast<size_t>(camera.width) * camera.height;
  std::vector<double> accum(4 * pixels, 0.0), revealage(pixels, 1.0);
  for (const Fragment& g : f) {
    const double d = zmax > zmin ? (g.depth - zmin) / (zmax - zmin) : 0.0;
    const double w = g.alpha * std::max(1e-2, 3e3 * std::pow(1.0 - d, 3.0));  // eq. 10
    double rgb[3];
    Unpack(g.key, rgb);
    for (int c = 0; c < 3; ++c) accum[4 * g.pixel + c] += rgb[c] * g.alpha * w;
    accum[4 * g.pixel + 3] += g.alpha * w;
    revealage[g.pixel] *= 1.0 - g.alpha;
  }
  ImageF image(camera.width, camera.height, 3);
  const double bg[3] = {double(options.background.r), double(options.background.g), double(options.background.b)};
  for (size_t p = 0; p < pixels; ++p) {
    const double a = std::max(accum[4 * p + 3], 1e-5);
    for (int c = 0; c < 3; ++c) {
      const double v = accum[4 * p + c] / a * (1.0 - revealage[p]) + bg[c] * revealage[p];
      image.data()[3 * p + c] = static_cast<float>(v);
    }
  }
  return image;
}

double Rmse(const ImageF& a, const ImageF& b) {
  CANDI_CHECK(a.width() == b.width() && a.height() == b.height() && a.channels() == b.channels())
      << "Rmse: images differ in size";
  double sum = 0;
  for (size_t i = 0; i < a.values().size(); ++i) {
    const double d = double(a.values()[i]) - b.values()[i];
    sum += d * d;
  }
  return a.values().empty() ? 0.0 : std::sqrt(sum / a.values().size());
}

}  // namespace candi::render
