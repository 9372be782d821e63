#include "compare/report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/check.h"
#include "core/colour_map.h"
#include "core/text_format.h"

namespace candi::compare {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A length for people: millimetres below a metre, metres above.
std::string Length(double metres) {
  if (std::isnan(metres)) return "n/a";
  if (std::abs(metres) < 1.0) return FormatSignificant(metres * 1000.0, 4) + " mm";
  return FormatSignificant(metres, 6) + " m";
}

std::string Share(double share) { return FormatSignificant(100.0 * share, 4) + " %"; }

// Percentile p (0..100) of sorted values, linear between the closest ranks.
double Percentile(const std::vector<double>& sorted, double p) {
  if (sorted.empty()) return kNaN;
  const double x = p / 100.0 * static_cast<double>(sorted.size() - 1);
  const size_t i = static_cast<size_t>(std::floor(x));
  if (i + 1 >= sorted.size()) return sorted.back();
  return sorted[i] + (sorted[i + 1] - sorted[i]) * (x - static_cast<double>(i));
}

std::string Hex(Rgb8 c) {
  char buf[8];
  std::snprintf(buf, sizeof(buf), "#%02x%02x%02x", c.r, c.g, c.b);
  return buf;
}

std::string Escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string Num(double v) { return FormatSignificant(v, 6); }

}  // namespace

void SummaryOptions::Check() const {
  CANDI_CHECK_OPTION(std::isfinite(tolerance) && tolerance >= 0, tolerance, "finite and >= 0");
  CANDI_CHECK_OPTION_IN(bins, 1, 10000);
  CANDI_CHECK_OPTION(std::isfinite(range) && range >= 0, range, "finite and >= 0 (0 = automatic)");
}

DeviationSummary Summarize(const DeviationResult& result, const SummaryOptions& options) {
  options.Check();
  DeviationSummary s;
  s.method = result.method;
  s.is_signed = result.method != Method::kC2C;
  s.count = result.distance.size();
  s.tolerance = options.tolerance;
  std::vector<double> values;
  values.reserve(result.distance.size());
  for (double d : result.distance) {
    if (!std::isnan(d)) values.push_back(d);
  }
  s.defined = values.size();
  s.undefined = s.count - s.defined;
  for (uint8_t f : result.significant) s.significant += f;
  if (values.empty()) {
    s.mean = s.std = s.rms = s.min = s.max = s.mean_abs = kNaN;
    s.bins.assign(static_cast<size_t>(options.bins), 0);
    return s;
  }
  double sum = 0, sum_abs = 0, sum_sq = 0;
  uint64_t within = 0;
  for (double d : values) {
    sum += d;
    sum_abs += std::abs(d);
    sum_sq += d * d;
    within += std::abs(d) <= options.tolerance ? 1 : 0;
  }
  const double n = static_cast<double>(values.size());
  s.mean = sum / n;
  s.mean_abs = sum_abs / n;
  s.rms = std::sqrt(sum_sq / n);
  double var = 0;
  for (double d : values) var += (d - s.mean) * (d - s.mean);
  s.std = values.size() > 1 ? std::sqrt(var / (n - 1)) : 0.0;
  s.within_tolerance = static_cast<double>(within) / n;
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  s.min = sorted.front();
  s.max = sorted.back();
  for (double p : {1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0}) {
    s.percentiles.emplace_back(p, Percentile(sorted, p));
  }
  double range = options.range;
  if (range == 0) {
    std::vector<double> magnitudes(values.size());
    for (size_t i = 0; i < values.size(); ++i) magnitudes[i] = std::abs(values[i]);
    std::sort(magnitudes.begin(), magnitudes.end());
    range = std::max(1e-6, Percentile(magnitudes, 99.0));
  }
  s.histogram_min = s.is_signed ? -range : 0.0;
  s.histogram_max = range;
  s.bins.assign(static_cast<size_t>(options.bins), 0);
  const double width = (s.histogram_max - s.histogram_min) / options.bins;
  for (double d : values) {
    if (d < s.histogram_min) {
      ++s.below;
    } else if (d > s.histogram_max) {
      ++s.above;
    } else {
      const int b = std::min(options.bins - 1, static_cast<int>((d - s.histogram_min) / width));
      ++s.bins[static_cast<size_t>(b)];
    }
  }
  return s;
}

std::string HistogramSvg(const DeviationSummary& s, const std::string& title) {
  constexpr int kW = 720, kH = 360, kLeft = 70, kRight = 45, kTop = 40, kBottom = 60;
  const int plot_w = kW - kLeft - kRight, plot_h = kH - kTop - kBottom;
  const uint64_t peak = s.bins.empty() ? 0 : *std::max_element(s.bins.begin(), s.bins.end());
  std::ostringstream svg;
  svg << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << kW << "\" height=\"" << kH
      << "\" viewBox=\"0 0 " << kW << " " << kH << "\" font-family=\"sans-serif\" font-size=\"12\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"" << kW / 2 << "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">"
      << Escape(title) << "</text>\n";
  const double lo = s.histogram_min, hi = s.histogram_max;
  auto x_of = [&](double v) { return kLeft + (v - lo) / (hi - lo) * plot_w; };
  const double bar_w = static_cast<double>(plot_w) / std::max<size_t>(1, s.bins.size());
  for (size_t b = 0; b < s.bins.size(); ++b) {
    if (s.bins[b] == 0 || peak == 0) continue;
    const double centre = lo + (static_cast<double>(b) + 0.5) * (hi - lo) / s.bins.size();
    const Rgb8 colour = s.is_signed ? DivergingColour(centre / hi) : SequentialColour(centre / hi);
    const double h = static_cast<double>(s.bins[b]) / static_cast<double>(peak) * plot_h;
    svg << "<rect x=\"" << Num(kLeft + b * bar_w) << "\" y=\"" << Num(kTop + plot_h - h)
        << "\" width=\"" << Num(bar_w) << "\" height=\"" << Num(h) << "\" fill=\"" << Hex(colour)
        << "\" stroke=\"#555\" stroke-width=\"0.3\"/>\n";
  }
  // Axes, ticks (five on x), the peak count on y.
  svg << "<line x1=\"" << kLeft << "\" y1=\"" << kTop + plot_h << "\" x2=\"" << kLeft + plot_w
      << "\" y2=\"" << kTop + plot_h << "\" stroke=\"black\"/>\n"
      << "<line x1=\"" << kLeft << "\" y1=\"" << kTop << "\" x2=\"" << kLeft << "\" y2=\""
      << kTop + plot_h << "\" stroke=\"black\"/>\n";
  for (int t = 0; t <= 4; ++t) {
    const double v = lo + (hi - lo) * t / 4.0;
    const double x = x_of(v);
    svg << "<line x1=\"" << Num(x) << "\" y1=\"" << kTop + plot_h << "\" x2=\"" << Num(x)
        << "\" y2=\"" << kTop + plot_h + 5 << "\" stroke=\"black\"/>\n"
        << "<text x=\"" << Num(x) << "\" y=\"" << kTop + plot_h + 19
        << "\" text-anchor=\"middle\">" << Escape(Length(v)) << "</text>\n";
  }
  svg << "<text x=\"" << kLeft - 6 << "\" y=\"" << kTop + 4 << "\" text-anchor=\"end\">" << peak
      << "</text>\n"
      << "<text x=\"" << kLeft - 6 << "\" y=\"" << kTop + plot_h << "\" text-anchor=\"end\">0</text>\n"
      << "<text x=\"18\" y=\"" << kTop + plot_h / 2 << "\" transform=\"rotate(-90 18 "
      << kTop + plot_h / 2 << ")\" text-anchor=\"middle\">points</text>\n";
  auto marker = [&](double v, const char* colour, const std::string& label, int dy) {
    if (!(v >= lo && v <= hi)) return;
    svg << "<line x1=\"" << Num(x_of(v)) << "\" y1=\"" << kTop << "\" x2=\"" << Num(x_of(v))
        << "\" y2=\"" << kTop + plot_h << "\" stroke=\"" << colour
        << "\" stroke-dasharray=\"4 3\"/>\n<text x=\"" << Num(x_of(v) + 4) << "\" y=\""
        << kTop + 12 + dy << "\" fill=\"" << colour << "\">" << Escape(label) << "</text>\n";
  };
  if (!std::isnan(s.mean)) marker(s.mean, "black", "mean " + Length(s.mean), 0);
  if (s.tolerance > 0) {
    marker(s.tolerance, "#b8860b", "+tolerance", 16);
    if (s.is_signed) marker(-s.tolerance, "#b8860b", "-tolerance", 16);
  }
  svg << "<text x=\"" << kW / 2 << "\" y=\"" << kH - 14 << "\" text-anchor=\"middle\">"
      << Escape((s.is_signed ? "signed distance" : "distance") + std::string(" (") +
                std::to_string(s.defined) + " points; " + std::to_string(s.below) +
                " below and " + std::to_string(s.above) + " above the range; " +
                std::to_string(s.undefined) + " undefined)")
      << "</text>\n</svg>\n";
  return svg.str();
}

std::string ReportMarkdown(const DeviationSummary& s, const ReportContext& c) {
  std::ostringstream md;
  md << "# Deviation of " << c.compared << " from " << c.reference << "\n\n"
     << "Method: **" << MethodName(s.method) << "**" << (c.settings.empty() ? "" : " (" + c.settings + ")")
     << ". Distances " << (s.is_signed ? "are signed (positive on the side the reference faces"
                                         " or its normals point)"
                                       : "are unsigned")
     << "; the output cloud `" << c.output_file << "` holds them per point in the field "
     << "`distance`" << (s.method == Method::kM3C2 ? ", with `lod95` and `significant`" : "")
     << ".\n\n";
  if (!c.histogram_file.empty()) md << "![histogram of the distances](" << c.histogram_file << ")\n\n";
  md << "| figure | value |\n|---|---|\n"
     << "| compared points | " << s.count << " |\n"
     << "| with a distance | " << s.defined << " |\n"
     << "| undefined (NaN) | " << s.undefined << " |\n"
     << "| mean | " << Length(s.mean) << " |\n"
     << "| standard deviation | " << Length(s.std) << " |\n"
     << "| RMS | " << Length(s.rms) << " |\n"
     << "| mean of \\|d\\| | " << Length(s.mean_abs) << " |\n"
     << "| min / max | " << Length(s.min) << " / " << Length(s.max) << " |\n";
  for (const auto& [p, v] : s.percentiles) {
    md << "| percentile " << FormatSignificant(p, 3) << " | " << Length(v) << " |\n";
  }
  md << "| within tolerance " << Length(s.tolerance) << " | "
     << (s.defined ? Share(s.within_tolerance) : "n/a") << " |\n";
  if (s.method == Method::kM3C2) {
    md << "| significant change (\\|d\\| > LoD95) | " << s.significant << " ("
       << (s.defined ? Share(static_cast<double>(s.significant) / s.defined) : "n/a") << ") |\n";
  }
  if (!c.warnings.empty()) {
    md << "\n## Warnings\n\n";
    for (const auto& w : c.warnings) md << "- " << w << "\n";
  }
  return md.str();
}

}  // namespace candi::compare
