// Exact, locale-independent number formatting and parsing for text formats.
#pragma once

#include <string>
#include <vector>

namespace candi {

// Shortest decimal text that parses back to exactly `value` (std::to_chars).
std::string FormatDouble(double value);
std::string FormatFloat(float value);

// At most `digits` (>= 1) significant digits, as printf's "%.<digits>g" (std::ostream's default
// notation at that precision): for messages and logs, where the shortest exact text is too long.
std::string FormatSignificant(double value, int digits);

// Writes the shortest round-trip text of value into buf (at least 48 bytes); returns the end.
// Fixed notation for magnitudes in [1e-4, 1e16) (floats: 1e7), scientific otherwise.
char* AppendDouble(char* buf, double value);
char* AppendFloat(char* buf, float value);

// Finite numbers separated by `separator` ("1,2,3", "1024x768"); throws
// std::invalid_argument("<what> '<text>': ...") naming the option or field they came from.
std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what);

}  // namespace candi
