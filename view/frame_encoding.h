// Frame encoding for the viewer: JPEG (libjpeg-turbo) while an image converges, PNG (libpng,
// lossless) once it has: the page then holds the exact pixels `candi render` writes.
#pragma once

#include <string>

#include "core/image.h"

namespace candi::view {

// RGB (3 channels) only. quality in [1, 100].
std::string EncodeJpeg(const Image8& image, int quality);
// Fast compression (zlib level 1, no filter search): the converged frame is sent once.
std::string EncodePng(const Image8& image);

}  // namespace candi::view
