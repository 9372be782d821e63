// Parsing of option values shared by the commands ("1,2,3", "1024x768").
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

namespace candi::app {

// Finite numbers separated by `separator`; throws std::invalid_argument("<what> '<text>': ...").
std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what);
// "x,y,z", a non-zero finite direction (std::invalid_argument naming `what` otherwise).
Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what);

}  // namespace candi::app
