#include "reconstruction/relief/relief_image.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <vector>

#include "core/check.h"
#include "io/image/jpeg_io.h"

namespace candi::relief {

namespace {

template <typename T>
ImageF GreyOf(const Image<T>& image, double full_scale) {
  ImageF grey(image.width(), image.height(), 1);
  const int c = image.channels();
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      double v = image.at(x, y, 0);
      if (c >= 3) v = 0.299 * image.at(x, y, 0) + 0.587 * image.at(x, y, 1) + 0.114 * image.at(x, y, 2);
      grey.at(x, y) = static_cast<float>(v / full_scale);
    }
  }
  return grey;
}

template <typename T>
bool IsGrey(const Image<T>& image) {
  if (image.channels() == 1) return true;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      if (image.at(x, y, 1) != image.at(x, y, 0) || image.at(x, y, 2) != image.at(x, y, 0)) {
        return false;
      }
    }
  }
  return true;
}

// The PNG signature (ReadPng gives the clear error for a damaged PNG).
bool IsPngFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char signature[8] = {};
  in.read(signature, sizeof(signature));
  static const char kPng[8] = {'\x89', 'P', 'N', 'G', '\r', '\n', '\x1a', '\n'};
  return !in || std::equal(signature, signature + 8, kPng);  // unreadable: ReadPng says why
}

float Clamped(float v, float lo, float hi) { return std::isnan(v) ? lo : std::clamp(v, lo, hi); }

// round(scale * clamp(v, 0, hi)) per pixel; NaN becomes 0.
template <typename T>
Image<T> Quantized(const ImageF& image, double hi, double scale) {
  CANDI_CHECK_EQ(image.channels(), 1);
  Image<T> out(image.width(), image.height(), 1);
  for (size_t i = 0; i < image.values().size(); ++i) {
    out.values()[i] = static_cast<T>(std::lround(scale * Clamped(image.values()[i], 0, static_cast<float>(hi))));
  }
  return out;
}

// One axis of Resample: `in` is n_in samples at stride `stride`, written to n_out samples.
void ResampleLine(const float* in, int n_in, int stride, float* out, int n_out, int out_stride) {
  const double scale = static_cast<double>(n_in) / n_out;
  for (int j = 0; j < n_out; ++j) {
    if (scale > 1.0) {  // area average of the input cells covered by [j, j+1) * scale
      const double a = j * scale, b = (j + 1) * scale;
      double sum = 0.0;
      for (int i = static_cast<int>(a); i < n_in && i < b; ++i) {
        const double w = std::min<double>(i + 1, b) - std::max<double>(i, a);
        sum += w * in[static_cast<size_t>(i) * stride];
      }
      out[static_cast<size_t>(j) * out_stride] = static_cast<float>(sum / scale);
    } else {  // bilinear between input pixel centres
      const double s = std::clamp((j + 0.5) * scale - 0.5, 0.0, n_in - 1.0);
      const int i0 = static_cast<int>(s);
      const int i1 = std::min(i0 + 1, n_in - 1);
      const double f = s - i0;
      out[static_cast<size_t>(j) * out_stride] = static_cast<float>(
          (1 - f) * in[static_cast<size_t>(i0) * stride] + f * in[static_cast<size_t>(i1) * stride]);
    }
  }
}

}  // namespace

ImageF GreyFromPng(const io::PngImage& png) {
  return png.bit_depth == 16 ? GreyOf(png.image16, 65535.0) : GreyOf(png.image8, 255.0);
}

ImageF ReadPhoto(const std::string& path, io::PngText* text) {
  if (!IsPngFile(path)) {  // a JPEG (the camera's own file), or a clear error naming the format
    if (text != nullptr) text->clear();
    return GreyOf(io::ReadImageRgb8(path), 255.0);
  }
  io::PngImage png = io::ReadPng(path);
  if (text != nullptr) *text = png.text;
  const ImageF grey = GreyFromPng(png);
  if (grey.empty()) throw InputError(path, "", "photo has no pixels");
  return grey;
}

void WritePhoto(const std::string& path, const ImageF& grey, const io::PngText& text) {
  io::WritePng(path, Quantized<uint8_t>(grey, 1, 255), text);
}

ImageF ReadDepth(const std::string& path, io::PngText* text) {
  io::PngImage png = io::ReadPng(path);
  if (text != nullptr) *text = png.text;
  const bool grey = png.bit_depth == 16 ? IsGrey(png.image16) : IsGrey(png.image8);
  if (!grey) throw InputError(path, "", "a depth map must be a grey PNG (this one has colour)");
  const double per_level = png.bit_depth == 16 ? 256.0 : 1.0;
  ImageF levels = png.bit_depth == 16 ? GreyOf(png.image16, per_level) : GreyOf(png.image8, per_level);
  if (levels.empty()) throw InputError(path, "", "depth map has no pixels");
  return levels;
}

void WriteDepth8(const std::string& path, const ImageF& levels, const io::PngText& text) {
  io::WritePng(path, Quantized<uint8_t>(levels, kMaxLevel, 1), text);
}

void WriteDepth16(const std::string& path, const ImageF& levels, const io::PngText& text) {
  io::WritePng(path, Quantized<uint16_t>(levels, kMaxLevel, 256), text);
}

ImageF Resample(const ImageF& image, int width, int height) {
  CANDI_CHECK_EQ(image.channels(), 1);
  CANDI_CHECK(width > 0 && height > 0 && !image.empty()) << width << "x" << height;
  if (width == image.width() && height == image.height()) return image;
  ImageF rows(width, image.height(), 1);
  for (int y = 0; y < image.height(); ++y) {
    ResampleLine(&image.at(0, y), image.width(), 1, &rows.at(0, y), width, 1);
  }
  ImageF out(width, height, 1);
  for (int x = 0; x < width; ++x) {
    ResampleLine(&rows.at(x, 0), image.height(), width, &out.at(x, 0), height, width);
  }
  return out;
}

ImageF GaussianBlur(const ImageF& image, double sigma) {
  CANDI_CHECK_EQ(image.channels(), 1);
  if (!(sigma > 0)) return image;
  const int r = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
  std::vector<double> k(2 * r + 1);
  double sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& v : k) v /= sum;
  const int w = image.width(), h = image.height();
  ImageF tmp(w, h, 1), out(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int i = -r; i <= r; ++i) s += k[i + r] * image.at(std::clamp(x + i, 0, w - 1), y);
      tmp.at(x, y) = static_cast<float>(s);
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int i = -r; i <= r; ++i) s += k[i + r] * tmp.at(x, std::clamp(y + i, 0, h - 1));
      out.at(x, y) = static_cast<float>(s);
    }
  }
  return out;
}

}  // namespace candi::relief
