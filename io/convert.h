// A point file rewritten in another format, streaming (any size): the output shift chosen, a CRS
// stated or reprojected with PROJ. What `candi convert` does.
// Failures: std::invalid_argument for invalid options, InputError naming the file otherwise (a
// file stating another CRS than options.crs, no CRS to reproject from, a point outside the target
// CRS's domain becomes NaN as io/crs.h says). The output is written atomically.
#pragma once

#include <optional>
#include <string>

#include "core/local_frame.h"
#include "core/progress.h"
#include "io/point_file.h"

namespace candi::io {

enum class ShiftChoice { kKeep, kAuto, kNone, kGiven };

struct ConvertOptions {
  PointReadOptions read;          // the input's XYZ/PTS columns
  PointWriteOptions write;        // the output's encoding, precision, LAS format, columns
  ShiftChoice shift = ShiftChoice::kKeep;  // kKeep: the input's (none after a reprojection); kAuto:
                                  // LocalFrame::Auto of the header's bounds (or the first chunk's)
  LocalFrame given_shift;         // with kGiven
  std::string crs;                // the input's CRS when the file states none ("" : as stated)
  std::string to_crs;             // reproject into this CRS ("" : no reprojection)
  void Check() const;
};

struct ConvertSummary {
  uint64_t points = 0;
  LocalFrame frame;               // the output's shift
};

// Streams `input` into `output`. `progress` is called with (0, total) once the output is open (an
// input or output that fails before then reports nothing), then after each chunk written.
ConvertSummary ConvertPointFile(const ConvertOptions& options, const std::string& input, const std::string& output,
                                const ProgressCallback& progress = nullptr);

}  // namespace candi::io
