// The 24 patches of the X-Rite ColorChecker Classic with their published 8-bit sRGB values (the
// widely reproduced X-Rite table, e.g. in Wikipedia's ColorChecker article), row by row from dark
// skin to black.
// Used as the reference of colour-card correction and by tests that synthesise a card.
#pragma once

#include <array>
#include <string>

#include <Eigen/Core>

namespace candi::testing {

struct ReferencePatch {
  const char* name;
  double r, g, b;  // sRGB, 0..255
  Eigen::Vector3d Rgb() const { return Eigen::Vector3d(r, g, b); }
};

const std::array<ReferencePatch, 24>& ColorChecker24();

}  // namespace candi::testing
