// Exact, locale-independent number formatting and parsing for text formats.
#pragma once

#include <string>

namespace candi {

// Shortest decimal text that parses back to exactly `value` (std::to_chars).
std::string FormatDouble(double value);
std::string FormatFloat(float value);

// Writes the shortest round-trip text of value into buf (at least 48 bytes); returns the end.
// Fixed notation for magnitudes in [1e-4, 1e16) (floats: 1e7), scientific otherwise.
char* AppendDouble(char* buf, double value);
char* AppendFloat(char* buf, float value);

}  // namespace candi
