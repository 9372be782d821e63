// A field colouring's legend drawn into an image (render/ has no font library: a 5x7 bitmap font,
// upper case, digits and a few signs, scaled to the image): the field's name, the colour bar
// with its range (or the classes present, each with its colour and name) and the grey of values
// outside the range or undefined, with their counts. Drawn on a darkened panel at the image's
// bottom left.
#pragma once

#include <string>

#include "core/field_colour.h"
#include "core/image.h"

namespace candi::render {

// Draws the legend onto `image` (3 or 4 channels). Returns false, drawing nothing, when the
// image is too small to hold it.
bool DrawFieldLegend(const FieldLegend& legend, Image8* image);

// A value as a legend prints it: 3 significant digits, no trailing zeros ("-0.0125", "1.5e+06").
std::string LegendNumber(double value);

// The text drawn in the 5x7 font at (x, y) (its top left), `scale` pixels a font pixel, in
// `colour`; characters the font lacks are drawn as '?'. Returns the width drawn, pixels.
int DrawText(const std::string& text, int x, int y, int scale, Rgb8 colour, Image8* image);

}  // namespace candi::render
