#include "render/legend.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

namespace candi::render {

namespace {

// 5x7 glyphs, one byte a row from the top, bit 4 the leftmost pixel.
struct Glyph {
  char c;
  uint8_t rows[7];
};

constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x11, 0x1F, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}}, {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}}, {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}}, {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}}, {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}}, {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}}, {' ', {0, 0, 0, 0, 0, 0, 0}},
    {'?', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x00, 0x04}},
};

const Glyph& GlyphOf(char c) {
  const char u = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  for (const Glyph& g : kFont) {
    if (g.c == u) return g;
  }
  return kFont[sizeof(kFont) / sizeof(kFont[0]) - 1];  // '?'
}

void Put(Image8* image, int x, int y, Rgb8 c) {
  if (x < 0 || y < 0 || x >= image->width() || y >= image->height()) return;
  image->at(x, y, 0) = c.r;
  image->at(x, y, 1) = c.g;
  image->at(x, y, 2) = c.b;
}

void Fill(Image8* image, int x0, int y0, int w, int h, Rgb8 c) {
  for (int y = y0; y < y0 + h; ++y) {
    for (int x = x0; x < x0 + w; ++x) Put(image, x, y, c);
  }
}

// Darkens a rectangle to 35 % of its brightness: the panel the legend is read against.
void Darken(Image8* image, int x0, int y0, int w, int h) {
  for (int y = std::max(0, y0); y < std::min(image->height(), y0 + h); ++y) {
    for (int x = std::max(0, x0); x < std::min(image->width(), x0 + w); ++x) {
      for (int k = 0; k < 3; ++k) image->at(x, y, k) = static_cast<uint8_t>((image->at(x, y, k) * 35 + 50) / 100);
    }
  }
}

int TextWidth(const std::string& text, int scale) { return static_cast<int>(text.size()) * 6 * scale - scale; }

std::string WithCount(const std::string& what, uint64_t n) { return what + " " + std::to_string(n); }

}  // namespace

std::string LegendNumber(double value) {
  if (value == 0) return "0";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", value);
  return buffer;
}

int DrawText(const std::string& text, int x, int y, int scale, Rgb8 colour, Image8* image) {
  int at = x;
  for (char c : text) {
    const Glyph& g = GlyphOf(c);
    for (int row = 0; row < 7; ++row) {
      for (int col = 0; col < 5; ++col) {
        if (g.rows[row] & (0x10 >> col)) Fill(image, at + col * scale, y + row * scale, scale, scale, colour);
      }
    }
    at += 6 * scale;
  }
  return at - x - (text.empty() ? 0 : scale);
}

bool DrawFieldLegend(const FieldLegend& legend, Image8* image) {
  if (image->channels() < 3) return false;
  const int s = std::max(1, static_cast<int>(std::lround(std::min(image->width(), image->height()) / 400.0)));
  const Rgb8 white{255, 255, 255};
  const int margin = 8 * s, pad = 5 * s, line = 10 * s, bar_height = 9 * s;
  std::vector<std::string> lines;  // the lines under the bar (or the classes)
  std::string title = legend.field;
  int width = 0, height = 0;
  if (legend.scale == FieldScale::kClasses) {
    constexpr size_t kMaxRows = 12;
    for (size_t i = 0; i < legend.classes.size() && i < kMaxRows; ++i) {
      lines.push_back(std::to_string(legend.classes[i]) + " " + ClassName(legend.classes[i]));
    }
    if (legend.classes.size() > kMaxRows) lines.push_back("+" + std::to_string(legend.classes.size() - kMaxRows) + " more");
    for (const std::string& l : lines) width = std::max(width, 9 * s + TextWidth(l, s));
    height = line * static_cast<int>(lines.size());
  } else {
    width = 160 * s;
    height = bar_height + 2 * s + line;  // the bar and its numbers
  }
  std::string grey;
  if (legend.scale != FieldScale::kClasses) grey = WithCount("outside", legend.outside);
  if (legend.undefined > 0) grey += (grey.empty() ? "" : ", ") + WithCount("none", legend.undefined);
  width = std::max({width, TextWidth(title, s), grey.empty() ? 0 : 9 * s + TextWidth(grey, s)});
  height += line + (grey.empty() ? 0 : line);
  const int panel_w = width + 2 * pad, panel_h = height + 2 * pad - 3 * s;
  if (panel_w + 2 * margin > image->width() || panel_h + 2 * margin > image->height()) return false;
  const int x0 = margin, y0 = image->height() - margin - panel_h;
  Darken(image, x0, y0, panel_w, panel_h);
  int y = y0 + pad;
  DrawText(title, x0 + pad, y, s, white, image);
  y += line;
  if (legend.scale == FieldScale::kClasses) {
    for (size_t i = 0; i < lines.size(); ++i) {
      if (i < legend.classes.size()) Fill(image, x0 + pad, y, 7 * s, 7 * s, ClassColour(legend.classes[i]));
      DrawText(lines[i], x0 + pad + 9 * s, y, s, white, image);
      y += line;
    }
  } else {
    const int bar_w = width;
    for (int i = 0; i < bar_w; ++i) {
      const double v = legend.lo + (legend.hi - legend.lo) * (i + 0.5) / bar_w;
      Fill(image, x0 + pad + i, y, 1, bar_height, legend.Colour(v));
    }
    y += bar_height + 2 * s;
    const std::string lo = LegendNumber(legend.lo), hi = LegendNumber(legend.hi);
    const std::string mid = LegendNumber(legend.scale == FieldScale::kDiverging && legend.lo == -legend.hi
                                             ? 0.0 : 0.5 * (legend.lo + legend.hi));
    DrawText(lo, x0 + pad, y, s, white, image);
    DrawText(mid, x0 + pad + (bar_w - TextWidth(mid, s)) / 2, y, s, white, image);
    DrawText(hi, x0 + pad + bar_w - TextWidth(hi, s), y, s, white, image);
    y += line;
  }
  if (!grey.empty()) {
    Fill(image, x0 + pad, y, 7 * s, 7 * s, kOutOfRangeGrey);
    DrawText(grey, x0 + pad + 9 * s, y, s, white, image);
  }
  return true;
}

}  // namespace candi::render
