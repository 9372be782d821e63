// JPEG reading and writing (libjpeg-turbo), 8-bit grey or RGB; and ReadImageRgb8, which reads a
// photo in either PNG or JPEG (chosen by the file's signature, not its extension) as 8-bit RGB.
//
// candi reads photos through these rather than OpenCV's imgcodecs: that library pulls in ~120
// shared libraries (GDAL, GDCM, HDF5, Poppler, ...) whose symbol binding cost every `candi`
// call about 0.8 s of start-up. Writes are atomic (temporary file, then rename). Errors throw
// InputError with libjpeg's message, naming the path for files. Thread-safe (no shared state).
#pragma once

#include <string>

#include "core/image.h"

namespace candi::io {

// Grey files give 1 channel, colour (YCbCr/RGB) files 3; CMYK/YCCK files are refused with a clear
// error.
Image8 ReadJpeg(const std::string& path);
// A JPEG's bytes in memory (the viewer's frames). quality in [1, 100]; 1- or 3-channel images
// (4 channels: the alpha is dropped). libjpeg's defaults otherwise (4:2:0 chroma, baseline).
std::string EncodeJpeg(const Image8& image, int quality = 95);
// EncodeJpeg's bytes, written atomically.
void WriteJpeg(const std::string& path, const Image8& image, int quality = 95);

// What a camera writes about its lens, as EXIF (an APP1 segment after the JFIF header): Make,
// Model, FocalLength (mm), FocalPlaneX/YResolution (pixels per cm of the sensor, from its width),
// FocalPlaneResolutionUnit (cm) and PixelX/YDimension. COLMAP's extractor turns them into a focal
// prior in pixels: focal_mm / sensor_width_mm * max(width, height). Readers show FocalLength to
// 0.1 mm, so a focal_mm on that grid keeps the prior exact.
struct JpegExif {
  std::string make = "candi", model = "synthetic";  // ASCII, no NUL
  double focal_mm = 0;                               // > 0
  double sensor_width_mm = 0;                        // > 0, the sensor's width along the image's x
};
// EncodeJpeg's bytes with the EXIF segment inserted. Throws std::invalid_argument for a
// non-positive focal or sensor width.
std::string EncodeJpegWithExif(const Image8& image, const JpegExif& exif, int quality = 95);
// The focal length in pixels a reader derives from `exif` for an image `width` pixels wide.
double ExifFocalPixels(const JpegExif& exif, int width);

// A PNG or JPEG as 8-bit RGB: grey is replicated, alpha dropped, 16 bits scaled (v * 255 / 65535,
// rounded). Other formats (TIFF, BMP, ...) fail with InputError naming the path and the format.
Image8 ReadImageRgb8(const std::string& path);

}  // namespace candi::io
