// Grey images and depth maps of relief panels: the one depth convention, PNG reading/writing,
// resampling and blur.
//
// Depth convention (used by every relief command, the network and the metrics): a depth map holds
// *depth levels* 0..255 measured from the panel's front plane, the plane z = depth_m of the panel
// frame (x along the wall, y up, z out of the wall; the wall is z = 0). Level 0 is the front plane,
// level 255 the wall: level = 255 * (depth_m - z) / depth_m, so z = depth_m * (1 - level / 255).
// Levels below kMinValidLevel (the front-most 0.4 % of the range) are treated as "no data" (the
// metrics and the loss mask them, as the paper masks zero depths).
//
// Files: photos are 8- or 16-bit PNGs, grey or colour (colour becomes luminance, Rec. 601;
// alpha is ignored), read as float in [0, 1]. Depth maps are grey PNGs: 8-bit = levels, 16-bit =
// levels * 256 (sub-level precision, used for training pairs). All writes are atomic. Bad files
// throw InputError naming the path.
#pragma once

#include <string>

#include "core/image.h"
#include "io/image/png_io.h"

namespace candi::relief {

constexpr double kMaxLevel = 255.0;
constexpr double kMinValidLevel = 1.0;

// Depth level of a height z (metres above the wall) for a relief of depth_m; and back.
inline double LevelFromHeight(double z, double depth_m) { return kMaxLevel * (depth_m - z) / depth_m; }
inline double HeightFromLevel(double level, double depth_m) {
  return depth_m * (1.0 - level / kMaxLevel);
}

// A one-channel float image of a PNG: 8-bit values / 255, 16-bit / 65535, colour as luminance.
ImageF GreyFromPng(const io::PngImage& png);
// Reads a photo (PNG, or JPEG as cameras write them) as grey [0, 1]. Throws InputError (path)
// for unreadable files and other formats.
ImageF ReadPhoto(const std::string& path, io::PngText* text = nullptr);
// Writes grey [0, 1] as an 8-bit PNG (clamped, rounded; NaN becomes 0).
void WritePhoto(const std::string& path, const ImageF& grey, const io::PngText& text = {});

// Reads a depth map as float levels (see the convention above). Throws InputError when the file
// is not a one-channel (or grey RGB) PNG.
ImageF ReadDepth(const std::string& path, io::PngText* text = nullptr);
// Writes levels as an 8-bit PNG (0..255, rounded, clamped; NaN becomes 0).
void WriteDepth8(const std::string& path, const ImageF& levels, const io::PngText& text = {});
// Writes levels as a 16-bit PNG (levels * 256).
void WriteDepth16(const std::string& path, const ImageF& levels, const io::PngText& text = {});

// Resamples a one-channel image to width x height: area averaging along an axis that shrinks,
// bilinear (pixel centres aligned) along an axis that grows.
ImageF Resample(const ImageF& image, int width, int height);
// Separable Gaussian blur, borders clamped; sigma in pixels (<= 0: a copy).
ImageF GaussianBlur(const ImageF& image, double sigma);

}  // namespace candi::relief
