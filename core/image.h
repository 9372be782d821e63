// Image: a row-major, interleaved raster of T with 1, 3 or 4 channels.
#pragma once

#include <cstdint>
#include <vector>

#include "core/check.h"

namespace candi {

template <typename T>
class Image {
 public:
  Image() = default;
  Image(int width, int height, int channels, T fill = T())
      : width_(width), height_(height), channels_(channels) {
    CANDI_CHECK(width >= 0 && height >= 0) << width << "x" << height;
    CANDI_CHECK(channels == 1 || channels == 3 || channels == 4) << "channels = " << channels;
    data_.assign(static_cast<size_t>(width) * height * channels, fill);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  int channels() const { return channels_; }
  bool empty() const { return data_.empty(); }

  T& at(int x, int y, int c = 0) { return data_[Index(x, y, c)]; }
  const T& at(int x, int y, int c = 0) const { return data_[Index(x, y, c)]; }
  T* data() { return data_.data(); }
  const T* data() const { return data_.data(); }
  std::vector<T>& values() { return data_; }
  const std::vector<T>& values() const { return data_; }

  bool operator==(const Image& o) const {
    return width_ == o.width_ && height_ == o.height_ && channels_ == o.channels_ && data_ == o.data_;
  }

 private:
  size_t Index(int x, int y, int c) const {
    return (static_cast<size_t>(y) * width_ + x) * channels_ + c;
  }
  int width_ = 0, height_ = 0, channels_ = 0;
  std::vector<T> data_;
};

using Image8 = Image<uint8_t>;
using Image16 = Image<uint16_t>;
using ImageF = Image<float>;

}  // namespace candi
