#include "section/section_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>


namespace candi::section {

namespace {

// Glyph widths of the scale bar's font: 'm' is five pixels wide, the others three.
int GlyphWidth(char c) { return c == 'm' ? 5 : 3; }

// A 5-pixel-high font for the scale bar's label: digits, '.', 'm', 'k', 'c' (rows top to bottom,
// GlyphWidth bits each, the high bit left).
int Glyph(char c, int row) {
  static const int kDigits[10][5] = {{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7},
                                     {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 2, 2, 2},
                                     {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}};
  if (c >= '0' && c <= '9') return kDigits[c - '0'][row];
  static const int kDot[5] = {0, 0, 0, 0, 2}, kM[5] = {0, 0, 30, 21, 21}, kK[5] = {4, 5, 6, 5, 5}, kC[5] = {0, 0, 7, 4, 7};
  switch (c) {
    case '.': return kDot[row];
    case 'm': return kM[row];
    case 'k': return kK[row];
    case 'c': return kC[row];
    default: return 0;
  }
}

void Fill(Image8* image, int x0, int y0, int x1, int y1, Rgb8 c) {
  for (int y = std::max(0, y0); y < std::min(image->height(), y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(image->width(), x1); ++x) {
      image->at(x, y, 0) = c.r;
      image->at(x, y, 1) = c.g;
      image->at(x, y, 2) = c.b;
    }
  }
}

std::string LengthLabel(double metres) {
  char text[32];
  if (metres >= 1000) {
    std::snprintf(text, sizeof(text), "%gkm", metres / 1000);
  } else if (metres >= 1) {
    std::snprintf(text, sizeof(text), "%gm", metres);
  } else if (metres >= 0.01) {
    std::snprintf(text, sizeof(text), "%gcm", metres * 100);
  } else {
    std::snprintf(text, sizeof(text), "%gmm", metres * 1000);
  }
  return text;
}

std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.6f", v);
  return text;
}

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

std::string Hex(Rgb8 c) {
  char text[8];
  std::snprintf(text, sizeof(text), "#%02x%02x%02x", c.r, c.g, c.b);
  return text;
}

double RoundLength(double target) {
  const double p = std::pow(10.0, std::floor(std::log10(target)));
  for (double m : {5.0, 2.0, 1.0}) {
    if (m * p <= target) return m * p;
  }
  return p;
}

}  // namespace

double DrawScaleBar(const SectionWindow& w, Rgb8 background, Image8* image) {
  const double metres = RoundLength(0.2 * w.width * w.metres_per_pixel);
  const int pixels = std::max(1, static_cast<int>(std::lround(metres / w.metres_per_pixel)));
  const bool dark = background.r + background.g + background.b < 384;
  const Rgb8 ink = dark ? Rgb8{255, 255, 255} : Rgb8{0, 0, 0};
  const int scale = std::max(1, w.height / 200);  // glyph pixels per font pixel
  const int x0 = 10 * scale, y1 = image->height() - 8 * scale;
  Fill(image, x0, y1 - scale, x0 + pixels, y1 + scale, ink);                 // the bar
  Fill(image, x0 - scale, y1 - 4 * scale, x0 + scale, y1 + scale, ink);       // ticks
  Fill(image, x0 + pixels - scale, y1 - 4 * scale, x0 + pixels + scale, y1 + scale, ink);
  const std::string label = LengthLabel(metres);
  int x = x0 + pixels + 4 * scale;
  for (char c : label) {
    const int width = GlyphWidth(c);
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col < width; ++col) {
        if (Glyph(c, row) & ((1 << (width - 1)) >> col)) {
          const int px = x + col * scale, py = y1 - 5 * scale + row * scale;
          Fill(image, px, py, px + scale, py + scale, ink);
        }
      }
    }
    x += (width + 1) * scale;
  }
  return metres;
}

std::string SectionCsv(const std::vector<SectionLayerResult>& layers, const SectionPath& section) {
  std::string out = "layer,line,vertex,closed,x,y,X,Y,Z\n";
  for (const SectionLayerResult& l : layers) {
    for (size_t k = 0; k < l.lines.size(); ++k) {
      const Polyline2& line = l.lines[k];
      for (size_t i = 0; i < line.points.size(); ++i) {
        const Eigen::Vector3d w = section.ToWorld(line.points[i]);
        out += l.name + "," + std::to_string(k) + "," + std::to_string(i) + "," + (line.closed ? "1" : "0") + "," +
               Num(line.points[i].x()) + "," + Num(line.points[i].y()) + "," + Num(w.x()) + "," + Num(w.y()) + "," +
               Num(w.z()) + "\n";
      }
    }
  }
  return out;
}

std::string SectionSvg(const std::vector<SectionLayerResult>& layers, const SectionWindow& w,
                       const std::string& image_href, const std::string& title, double bar_metres) {
  const double width_m = w.width * w.metres_per_pixel, height_m = w.height * w.metres_per_pixel;
  // SVG y runs down: drawing y maps to -y, so the viewBox's top is -(y0 + height).
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"" +
         std::to_string(w.width) + "\" height=\"" + std::to_string(w.height) + "\" viewBox=\"" + Num(w.x0) + " " +
         Num(-(w.y0 + height_m)) + " " + Num(width_m) + " " + Num(height_m) + "\">\n";
  out += "<title>" + Escape(title) + "</title>\n";
  if (!image_href.empty()) {
    out += "<image id=\"section-image\" xlink:href=\"" + Escape(image_href) + "\" href=\"" + Escape(image_href) +
           "\" x=\"" + Num(w.x0) + "\" y=\"" + Num(-(w.y0 + height_m)) + "\" width=\"" + Num(width_m) +
           "\" height=\"" + Num(height_m) + "\" preserveAspectRatio=\"none\" opacity=\"0.6\"/>\n";
  }
  for (const SectionLayerResult& l : layers) {
    out += "<g id=\"layer-" + Escape(l.name) + "\" stroke=\"" + Hex(l.colour) +
           "\" fill=\"none\" stroke-width=\"2\" vector-effect=\"non-scaling-stroke\">\n";
    for (const Polyline2& line : l.lines) {
      out += line.closed ? "<polygon points=\"" : "<polyline points=\"";
      for (size_t i = 0; i < line.points.size(); ++i) {
        out += (i ? " " : "") + Num(line.points[i].x()) + "," + Num(-line.points[i].y());
      }
      out += "\" vector-effect=\"non-scaling-stroke\"/>\n";
    }
    out += "</g>\n";
  }
  // Scale bar and legend in pixels of the drawing (a group scaled to metres).
  const double px = w.metres_per_pixel, left = w.x0 + 10 * px, base = -(w.y0) - 30 * px;
  out += "<g id=\"scale-bar\" stroke=\"black\" stroke-width=\"" + Num(2 * px) + "\">\n<line x1=\"" + Num(left) +
         "\" y1=\"" + Num(base) + "\" x2=\"" + Num(left + bar_metres) + "\" y2=\"" + Num(base) + "\"/>\n";
  out += "<text x=\"" + Num(left + bar_metres + 6 * px) + "\" y=\"" + Num(base + 5 * px) + "\" font-size=\"" +
         Num(14 * px) + "\" stroke=\"none\" font-family=\"sans-serif\">" + LengthLabel(bar_metres) + "</text>\n</g>\n";
  out += "<g id=\"legend\" font-family=\"sans-serif\" font-size=\"" + Num(14 * px) + "\">\n";
  double y = -(w.y0 + height_m) + 20 * px;
  for (const SectionLayerResult& l : layers) {
    std::string note = l.area ? " (in the plane: an area, no line)" : l.points == 0 ? " (no points in the slab)" : "";
    out += "<text x=\"" + Num(left) + "\" y=\"" + Num(y) + "\" fill=\"" + Hex(l.colour) + "\">" + Escape(l.name) +
           Escape(note) + "</text>\n";
    y += 18 * px;
  }
  out += "<text x=\"" + Num(left) + "\" y=\"" + Num(y) + "\" fill=\"gray\">" + Escape(title) + "</text>\n</g>\n";
  out += "</svg>\n";
  return out;
}

}  // namespace candi::section
