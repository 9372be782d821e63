// Tokenizing and exact number parsing for the text point formats (io/xyz/xyz_io.cc).
//
// Values are separated by blanks (runs count as one) or by one ',' or ';' with optional blanks
// around it. The parsers rely on a sentinel: every parsed line is followed by a byte that is no
// digit, sign, '.' or 'e' ('\n' in the mapped text, '\0' after a std::string).
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string_view>
#include <vector>

namespace candi::io::text_scan {

// '\r' is a blank, so CRLF files need no special case.

// One table look-up per character rather than a chain of comparisons.
constexpr uint8_t kBlank = 1, kComma = 2;  // kComma: ',' or ';'
struct CharClasses {
  uint8_t bits[256] = {};
  constexpr CharClasses() {
    bits[' '] = bits['\t'] = bits['\r'] = bits['\v'] = bits['\f'] = kBlank;
    bits[','] = bits[';'] = kComma;
  }
};
constexpr CharClasses kChars;
inline bool IsBlank(char c) { return kChars.bits[static_cast<uint8_t>(c)] == kBlank; }
inline bool IsComma(char c) { return kChars.bits[static_cast<uint8_t>(c)] == kComma; }
inline bool IsSeparator(char c) { return kChars.bits[static_cast<uint8_t>(c)] != 0; }

inline const char* SkipBlanks(const char* p) {
  while (IsBlank(*p)) ++p;
  return p;
}

// From the end of a value to the start of the next one (the line's end when there is none).
inline const char* NextValue(const char* p) {
  p = SkipBlanks(p);
  if (IsComma(*p)) p = SkipBlanks(p + 1);
  return p;
}

inline std::vector<std::string_view> SplitLine(const char* p, const char* end) {
  std::vector<std::string_view> tokens;
  for (p = SkipBlanks(p); p != end;) {
    const char* q = p;
    while (q != end && !IsSeparator(*q)) ++q;
    tokens.emplace_back(p, static_cast<size_t>(q - p));
    p = NextValue(q);
  }
  return tokens;
}

inline bool IsDigit(char c) { return static_cast<unsigned char>(c - '0') < 10; }

// The fast number parsers rely on a sentinel instead of checking the end at every character:
// every parsed line is followed by a byte that is no digit, sign, '.' or 'e' ('\n' in the mapped
// text, '\0' after a std::string: the file's last line is copied), and every value within a line
// by a separator.

// Exact decimal to double without std::from_chars (which libstdc++ 12 implements with strtod,
// ~100 ns a value) in the common case. Clinger's fast path (W. D. Clinger, "How to read floating
// point numbers accurately", PLDI 1990): for w < 2^53 and |e| <= 22 both w and 10^|e| are exact
// doubles, so w * 10^e or w / 10^-e is one correctly rounded operation, i.e. the exact result.
// Returns false (nothing parsed) when the text is outside that case.
inline bool FastNumber(const char* p, double* value, const char** stop) {
  static constexpr double kPow10[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                      1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                      1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const bool negative = *p == '-';
  p += negative;
  uint64_t w = 0;  // may wrap for > 19 digits, which are then rejected
  const char* first = p;
  while (IsDigit(*p)) w = 10 * w + static_cast<uint64_t>(*p++ - '0');
  int exponent = 0, digits = static_cast<int>(p - first);
  if (*p == '.') {
    const char* fraction = ++p;
    while (IsDigit(*p)) w = 10 * w + static_cast<uint64_t>(*p++ - '0');
    exponent = -static_cast<int>(p - fraction);
    digits -= exponent;
  }
  if (digits == 0 || digits > 19) return false;  // not a plain decimal, or w may have wrapped
  if (*p == 'e' || *p == 'E') {
    const bool e_negative = *++p == '-';
    p += *p == '-' || *p == '+';
    const char* e = p;
    int n = 0;
    for (; IsDigit(*p) && n < 1000; ++p) n = 10 * n + (*p - '0');
    if (p == e) return false;
    exponent += e_negative ? -n : n;
  }
  if (w > (uint64_t{1} << 53) || exponent < -22 || exponent > 22) return false;
  const double d = static_cast<double>(w);
  *value = exponent < 0 ? d / kPow10[-exponent] : d * kPow10[exponent];
  if (negative) *value = -*value;
  *stop = p;
  return true;
}

// Float through the double fast path: rounding the exact-rounded double to float is exact unless
// the double lies exactly on a midpoint between floats (then from_chars decides).
inline bool FastNumber(const char* p, float* value, const char** stop) {
  double d;
  if (!FastNumber(p, &d, stop)) return false;
  const double magnitude = std::fabs(d);
  if (magnitude != 0.0 && !(magnitude >= 0x1p-126 && magnitude < 0x1p127)) return false;
  uint64_t bits;
  std::memcpy(&bits, &d, sizeof(bits));
  if ((bits & ((uint64_t{1} << 29) - 1)) == (uint64_t{1} << 28)) return false;  // a midpoint
  *value = static_cast<float>(d);
  return true;
}

inline bool FastNumber(const char* p, int* value, const char** stop) {
  const char* first = p;
  uint64_t n = 0;
  while (IsDigit(*p)) n = 10 * n + static_cast<uint64_t>(*p++ - '0');
  if (p == first || p - first > 9) return false;
  *value = static_cast<int>(n);
  *stop = p;
  return true;
}
inline bool FastNumber(const char*, uint64_t*, const char**) { return false; }

// Parses a number that spans a whole value; returns its end, or nullptr if it is not one.
template <typename T>
inline const char* ParseNumber(const char* p, const char* end, T* value) {
  if (*p == '+') ++p;  // from_chars does not take a leading '+'
  const char* ptr = nullptr;
  if (!FastNumber(p, value, &ptr)) {
    const auto result = std::from_chars(p, end, *value);
    if (result.ec != std::errc()) return nullptr;
    ptr = result.ptr;
  }
  return ptr == end || IsSeparator(*ptr) ? ptr : nullptr;
}

template <typename T>
bool IsNumber(std::string_view token, T* value) {
  const char* end = token.data() + token.size();
  return !token.empty() && ParseNumber(token.data(), end, value) == end;
}

}  // namespace candi::io::text_scan
