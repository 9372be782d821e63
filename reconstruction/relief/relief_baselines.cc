#include "reconstruction/relief/relief_baselines.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "core/check.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Angular frequency (radians per pixel) of DFT bin k of n, in (-pi, pi].
double Omega(int k, int n) { return 2 * kPi * (k <= n / 2 ? k : k - n) / n; }

}  // namespace

ImageF IntensityAsHeight(const ImageF& photo) { return photo; }

ImageF PentlandHeight(const ImageF& photo, double light_azimuth_deg, double light_elevation_deg) {
  CANDI_CHECK_EQ(photo.channels(), 1);
  CANDI_CHECK(light_elevation_deg > 0 && light_elevation_deg < 90) << light_elevation_deg;
  const int w = photo.width(), h = photo.height();
  // Mirror to 2w x 2h so the FFT sees a periodic image (no wrap-around edges).
  cv::Mat padded(2 * h, 2 * w, CV_64F);
  double mean = 0;
  for (float v : photo.values()) mean += std::isfinite(v) ? v : 0.0;
  mean /= std::max<size_t>(1, photo.values().size());
  for (int y = 0; y < 2 * h; ++y) {
    for (int x = 0; x < 2 * w; ++x) {
      const float v = photo.at(x < w ? x : 2 * w - 1 - x, y < h ? y : 2 * h - 1 - y);
      padded.at<double>(y, x) = (std::isfinite(v) ? v : mean) - mean;
    }
  }
  cv::Mat spectrum;
  cv::dft(padded, spectrum, cv::DFT_COMPLEX_OUTPUT);
  const double az = light_azimuth_deg * kPi / 180, el = light_elevation_deg * kPi / 180;
  const double lx = std::cos(el) * std::cos(az), ly = std::cos(el) * std::sin(az);
  // Small relative damping: keeps the division finite across the light direction.
  const double eps = 1e-4 * (lx * lx + ly * ly) * kPi * kPi;
  for (int y = 0; y < 2 * h; ++y) {
    const double wy = Omega(y, 2 * h);
    for (int x = 0; x < 2 * w; ++x) {
      const double d = -wy * ly - Omega(x, 2 * w) * lx;  // D = i d; rows run down: w_up = -w_row
      cv::Vec2d& s = spectrum.at<cv::Vec2d>(y, x);
      // Z = F(I) conj(D) / (|D|^2 + eps) with conj(D) = -i d.
      const double g = d / (d * d + eps);
      s = cv::Vec2d(s[1] * g, -s[0] * g);
    }
  }
  cv::Mat z;
  cv::idft(spectrum, z, cv::DFT_REAL_OUTPUT | cv::DFT_SCALE);
  ImageF out(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) out.at(x, y) = static_cast<float>(z.at<double>(y, x));
  }
  return out;
}

ImageF FitLevels(const ImageF& relative, const ImageF& truth) {
  CANDI_CHECK(relative.width() == truth.width() && relative.height() == truth.height());
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < truth.values().size(); ++i) {
    const double g = truth.values()[i], r = relative.values()[i];
    if (!std::isfinite(g) || g < kMinValidLevel || !std::isfinite(r)) continue;
    const double height = kMaxLevel - g;  // the baseline predicts height: nearer = larger
    n += 1, sx += r, sy += height, sxx += r * r, sxy += r * height;
  }
  double a = 0, b = kMaxLevel / 2;
  if (n > 0) {
    const double var = sxx - sx * sx / n;
    a = var > 1e-12 * n ? (sxy - sx * sy / n) / var : 0.0;
    b = (sy - a * sx) / n;
  }
  ImageF levels(relative.width(), relative.height(), 1);
  for (size_t i = 0; i < levels.values().size(); ++i) {
    const double r = std::isfinite(relative.values()[i]) ? relative.values()[i] : 0.0;
    levels.values()[i] = static_cast<float>(std::clamp(kMaxLevel - (a * r + b), 0.0, kMaxLevel));
  }
  return levels;
}

}  // namespace candi::relief
