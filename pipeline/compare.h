// `candi compare`: the deviation of a compared point file from a reference point file or mesh
// (compare/deviation.h), written as the compared cloud with the distances as scalar fields (PLY,
// LAS extra bytes, any point format candi writes), a JSON summary, the histogram as SVG and a
// Markdown report naming both. Every file is written atomically; nothing is written when the
// inputs cannot be read. Failures: InputError naming the file (unreadable, empty, a mesh without
// faces), std::invalid_argument for bad options.
#pragma once

#include <string>
#include <vector>

#include "compare/deviation.h"
#include "compare/report.h"
#include "core/progress.h"

namespace candi::pipeline {

struct CompareOptions {
  compare::DeviationOptions deviation;
  compare::SummaryOptions summary;
  std::string columns;  // XYZ/PTS column spec of text point files (io/xyz)
  void Check() const;
};

// What a comparison wrote, and its figures.
struct CompareOutcome {
  compare::DeviationResult result;
  compare::DeviationSummary summary;
  std::string cloud, json, histogram, report;  // the files written
};

// Reads `reference` (a point file; for C2M a mesh: PLY or OBJ, read in double) and `compared`,
// compares, and writes `output` (the cloud; its format by extension) and beside it
// OUTPUT.compare.json, OUTPUT.histogram.svg and OUTPUT.report.md.
CompareOutcome RunCompare(const CompareOptions& options, const std::string& reference,
                          const std::string& compared, const std::string& output,
                          const ProgressCallback& progress = nullptr);

// The summary as JSON text (what OUTPUT.compare.json holds).
std::string CompareSummaryJson(const CompareOptions& options, const CompareOutcome& outcome,
                               const std::string& reference, const std::string& compared);

}  // namespace candi::pipeline
