#include "reconstruction/relief/relief_tiles.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/check.h"

namespace candi::relief {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Weight of offset t in [0, tile) of a tile with (or without) neighbours before and after:
// zero on the outermost overlap / 4 pixels (where the network sees its zero padding; the
// neighbour covers them), then a sin^2 rise over the rest of the overlap.
double Ramp(int t, int tile, int overlap, bool before, bool after) {
  double w = 1.0;
  if (overlap <= 0) return w;
  const int margin = overlap / 4;
  auto rise = [&](double d) {
    const double s = std::sin(0.5 * kPi * std::clamp((d - margin) / (overlap - margin), 0.0, 1.0));
    return s * s;
  };
  if (before) w = std::min(w, rise(t + 0.5));
  if (after) w = std::min(w, rise(tile - t - 0.5));
  return w;
}

// Reflect index i into [0, n) (mirror without repeating the edge pixel, period 2n - 2).
int Mirror(int i, int n) {
  if (n == 1) return 0;
  const int period = 2 * n - 2;
  i %= period;
  if (i < 0) i += period;
  return i < n ? i : period - i;
}

ImageF Crop(const ImageF& image, int x0, int y0, int w, int h) {
  ImageF out(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      out.at(x, y) = image.at(Mirror(x0 + x, image.width()), Mirror(y0 + y, image.height()));
    }
  }
  return out;
}

}  // namespace

void TileOptions::Check() const {
  CANDI_CHECK_OPTION_GE(tile, 8);
  CANDI_CHECK_OPTION(overlap >= 0 && overlap <= tile / 2, overlap,
                     "in [0, tile / 2 = " + std::to_string(tile / 2) + "]");
}

std::vector<int> TileStarts(int size, int tile, int overlap) {
  CANDI_CHECK(size >= tile && tile > overlap) << size << " " << tile << " " << overlap;
  const int count = size == tile ? 1 : 1 + static_cast<int>(std::ceil(double(size - tile) / (tile - overlap)));
  std::vector<int> starts(count, 0);
  for (int i = 1; i < count; ++i) {
    starts[i] = static_cast<int>(std::lround(double(i) * (size - tile) / (count - 1)));
  }
  return starts;
}

ImageF PredictTiled(const TileOptions& o, const ImageF& image, const TilePredictor& predict,
                    const ProgressCallback& progress) {
  o.Check();
  CANDI_CHECK(image.channels() == 1 && !image.empty());
  // Work on an image at least one tile in each direction (mirror padding), cropped at the end.
  const int w = std::max(image.width(), o.tile), h = std::max(image.height(), o.tile);
  const ImageF padded = (w == image.width() && h == image.height()) ? image : Crop(image, 0, 0, w, h);
  const std::vector<int> xs = TileStarts(w, o.tile, o.overlap), ys = TileStarts(h, o.tile, o.overlap);
  std::vector<double> sum(static_cast<size_t>(w) * h, 0.0), weight(sum.size(), 0.0);
  std::vector<double> wx(o.tile), wy(o.tile);
  uint64_t done = 0;
  for (size_t b = 0; b < ys.size(); ++b) {
    for (int t = 0; t < o.tile; ++t) wy[t] = Ramp(t, o.tile, o.overlap, b > 0, b + 1 < ys.size());
    for (size_t a = 0; a < xs.size(); ++a) {
      for (int t = 0; t < o.tile; ++t) wx[t] = Ramp(t, o.tile, o.overlap, a > 0, a + 1 < xs.size());
      const ImageF out = predict(Crop(padded, xs[a], ys[b], o.tile, o.tile));
      CANDI_CHECK(out.width() == o.tile && out.height() == o.tile && out.channels() == 1);
      for (int y = 0; y < o.tile; ++y) {
        for (int x = 0; x < o.tile; ++x) {
          const size_t k = static_cast<size_t>(ys[b] + y) * w + xs[a] + x;
          sum[k] += wx[x] * wy[y] * out.at(x, y);
          weight[k] += wx[x] * wy[y];
        }
      }
      if (progress) progress(++done, xs.size() * ys.size());
    }
  }
  ImageF result(image.width(), image.height(), 1);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      const size_t k = static_cast<size_t>(y) * w + x;
      result.at(x, y) = static_cast<float>(sum[k] / weight[k]);
    }
  }
  return result;
}

}  // namespace candi::relief
