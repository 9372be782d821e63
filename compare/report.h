// What a deviation map says in figures: count, mean, spread, percentiles, the share within a
// tolerance, a histogram; and the two things a user reads, the histogram as an SVG picture and a
// short Markdown report.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "compare/deviation.h"

namespace candi::compare {

struct SummaryOptions {
  double tolerance = 0.01;  // m, >= 0: |distance| <= tolerance counts as within
  int bins = 60;            // histogram bins, [1, 10000]
  // The histogram's (and a colour scale's) range, m, >= 0: signed distances [-range, range],
  // unsigned [0, range]; 0 = automatic (the 99th percentile of |distance|, at least 1e-6).
  double range = 0;
  void Check() const;
};

struct DeviationSummary {
  Method method = Method::kC2C;
  bool is_signed = false;  // C2M (signed) and M3C2 distances have a sign; C2C's do not
  uint64_t count = 0;      // compared points
  uint64_t defined = 0;    // with a distance (not NaN)
  uint64_t undefined = 0;
  // Over the defined distances, m (NaN when none is defined):
  double mean = 0, std = 0, rms = 0, min = 0, max = 0, mean_abs = 0;
  std::vector<std::pair<double, double>> percentiles;  // (percent, value): 1, 5, 25, 50, 75, 95, 99
  double tolerance = 0;
  double within_tolerance = 0;  // share of the defined distances with |d| <= tolerance, [0, 1]
  uint64_t significant = 0;     // M3C2: distances beyond their LoD95
  // Histogram over [histogram_min, histogram_max] in equal bins; values outside are counted
  // in below/above (and drawn grey).
  double histogram_min = 0, histogram_max = 0;
  std::vector<uint64_t> bins;
  uint64_t below = 0, above = 0;
};

DeviationSummary Summarize(const DeviationResult& result, const SummaryOptions& options);

// The histogram as a self-contained SVG picture (bars in the colour scale of the values,
// axes in metres, the mean and the tolerance marked, the counts outside the range stated).
std::string HistogramSvg(const DeviationSummary& summary, const std::string& title);

// What the report names besides the figures.
struct ReportContext {
  std::string reference, compared;   // file names as the user gave them
  std::string settings;              // one line: the method's settings
  std::string histogram_file;        // the picture's file name, relative to the report
  std::string output_file;           // the cloud with the fields
  std::vector<std::string> warnings;
};

std::string ReportMarkdown(const DeviationSummary& summary, const ReportContext& context);

}  // namespace candi::compare
