// XYZ and PTS text point files.
//
// XYZ: one point per line, numbers separated by spaces, tabs, commas or semicolons; lines that
// are empty or start with '#' or '//' are skipped; a first line that is not numeric is taken as a
// header and skipped. PTS (Leica): the first line is the point count, then lines
// "x y z intensity [r g b]". Columns follow a spec (PointReadOptions::columns); without one they
// are guessed from the first data line's column count and the guess is logged. Parsing uses
// std::from_chars (exact, locale-independent); writing uses the shortest round-trip text, so
// double positions survive a round trip exactly. Errors name the file and the line.
#pragma once

#include <memory>
#include <string>

#include "core/point_io.h"

namespace candi {

std::unique_ptr<PointReader> OpenXyzReader(const std::string& path, bool pts,
                                           const PointReadOptions& options);
std::unique_ptr<PointWriter> OpenXyzWriter(const std::string& path, bool pts,
                                           const PointWriteSpec& spec,
                                           const PointWriteOptions& options);

}  // namespace candi
