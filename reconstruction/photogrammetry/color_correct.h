// Colour-card correction: a 3x4 colour matrix fitted in linear RGB to a card's patches, applied to
// images and point colours, with colour differences before and after.
//
// Colour spaces: inputs and outputs are 8-bit (or 16-bit) sRGB; the fit works in linear RGB
// (IEC 61966-2-1 decoding): ref_lin ≈ M [meas_lin; 1], least squares over the patches. Colour
// differences are CIEDE2000 (G. Sharma, W. Wu, E. Dalal, "The CIEDE2000 color-difference formula",
// Color Res. Appl. 30(1), 2005) in CIELAB with the D65 white of sRGB.
// Robustness: each patch's leave-one-out prediction error (the patch predicted by the fit on the
// others) is compared with max(outlier_delta_e, median + k * 1.4826 * MAD); the worst patch above
// it is removed and the test repeated, at most max_outliers times. Removed patches are reported.
// Degeneracy: patches whose linear design [r g b 1] is rank-deficient (e.g. all grey: r = g = b)
// leave the matrix undetermined: InputError, not a guess; a poorly conditioned one is a warning.
//
// Patches CSV (header required): patch,measured_r,measured_g,measured_b,reference_r,reference_g,
// reference_b — sRGB values 0..255 (the measured colour of each patch in the photo and its
// reference value).
// Corners CSV (header required): patch,x0,y0,x1,y1,x2,y2,x3,y3,reference_r,reference_g,reference_b
// — the patch's four corners in the card photo, in order around the quad, pixels (x = column,
// y = row, the first pixel's centre at (0, 0)); the inner 50 % of the quad (bilinear parameters
// 0.25..0.75) is sampled and its per-channel median taken as the measured colour.
// Thread-safety: pure functions.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.h"
#include "core/point_cloud.h"

namespace candi::photogrammetry {

using ColorMatrix = Eigen::Matrix<double, 3, 4>;  // linear RGB: out = M [in; 1]

double SrgbToLinear(double v);   // v in [0, 1]
double LinearToSrgb(double v);   // clamps to [0, 1]
Eigen::Vector3d SrgbToLab(const Eigen::Vector3d& srgb255);  // CIELAB, D65
double DeltaE2000(const Eigen::Vector3d& lab1, const Eigen::Vector3d& lab2);

struct ColorPatch {
  std::string name;
  Eigen::Vector3d measured = Eigen::Vector3d::Zero();   // sRGB 0..255
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // sRGB 0..255
  int line = 0;
};
std::vector<ColorPatch> ReadColorPatches(const std::string& path);

struct PatchQuad {
  std::string name;
  std::array<Eigen::Vector2d, 4> corners;               // pixels, in order around the patch
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();  // sRGB 0..255
  int line = 0;
};
std::vector<PatchQuad> ReadPatchQuads(const std::string& path);
// Median colour of each quad's inner 50 % in an RGB(A) image. Throws InputError(quads_path, line)
// for a quad reaching outside the image or covering no pixel.
std::vector<ColorPatch> SamplePatches(const Image8& image, const std::vector<PatchQuad>& quads,
                                      const std::string& quads_path);

struct ColorCorrectionOptions {
  double outlier_delta_e = 10.0;  // > 0: a patch predicted worse than this (CIEDE2000) may be an outlier
  double outlier_k = 4.0;         // > 0: ... and worse than median + k * robust sigma
  int max_outliers = 2;           // >= 0: patches that may be removed
  void Check() const;
};

struct PatchDeltaE {
  std::string name;
  double before = 0, after = 0;  // CIEDE2000 of measured / corrected against the reference
  bool outlier = false;          // left out of the fit
};

struct ColorCorrection {
  ColorMatrix matrix = ColorMatrix::Identity();
  std::vector<PatchDeltaE> patches;
  double mean_before = 0, max_before = 0;  // over the patches kept in the fit
  double mean_after = 0, max_after = 0;
  double conditioning = 0;                 // smallest / largest singular value of the design
  std::vector<std::string> warnings;
};

// Needs >= 4 patches spanning RGB (else InputError naming the problem).
ColorCorrection FitColorCorrection(const ColorCorrectionOptions& options,
                                   const std::vector<ColorPatch>& patches);

Eigen::Vector3d ApplyColorMatrix(const ColorMatrix& m, const Eigen::Vector3d& srgb255);  // clamped
// RGB or RGBA images (alpha kept); throws std::invalid_argument for grey images.
void ApplyColorMatrix(const ColorMatrix& m, Image8* image);
void ApplyColorMatrix(const ColorMatrix& m, Image16* image);
// Point colours (the cloud must have colours: CANDI_CHECK).
void ApplyColorMatrix(const ColorMatrix& m, PointCloud* cloud);

}  // namespace candi::photogrammetry
