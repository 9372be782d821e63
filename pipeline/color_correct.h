// `candi colorcorrect`: colour-card correction of a PNG image or a point file's colours
// (photogrammetry/color_correct.h), from the card's patches to the corrected file and its report.
// The patches come from a CSV of measured and reference colours, or are sampled in a photo of the
// card inside their corners. Failures: std::invalid_argument for invalid options (neither or both
// kinds of patches, a PNG corrected into a point file or the other way round), InputError naming
// the file for unreadable or malformed inputs (points without colours, a grey image, a card photo
// that is not 8-bit) and a fit the patches leave undetermined. Not thread-safe (writes files).
#pragma once

#include <functional>
#include <string>

#include "reconstruction/photogrammetry/color_correct.h"

namespace candi::pipeline {

// Where the card's patches come from: `patches`, or both `card` and `corners`.
struct ColorCard {
  // CSV: patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b (0..255)
  std::string patches;
  std::string card;     // a photo of the card (8-bit PNG)
  std::string corners;  // CSV: patch,x0,y0,...,x3,y3,reference_r,reference_g,reference_b (pixels)
};

// The correction fitted to the card and applied to `input` (a PNG, or a point file with colours),
// written as `output` (the same kind; a PNG keeps its bit depth and text), with
// OUTPUT.colorcorrect.json. `fitted` (may be null) gets the fit before anything is written; its
// warnings are logged.
photogrammetry::ColorCorrection ColorCorrectFile(
    const photogrammetry::ColorCorrectionOptions& options, const ColorCard& card,
    const std::string& input, const std::string& output,
    const std::function<void(const photogrammetry::ColorCorrection&)>& fitted = nullptr);

}  // namespace candi::pipeline
