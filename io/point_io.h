// Point files of any format: detection by extension confirmed by content, and the readers and
// writers of io/point_file.h opened for a path. DXF is an error (a drawing, not a point file);
// a content that contradicts the extension is an error, never a guess. Bad input throws
// InputError("<path>: <position>: <what>").
#pragma once

#include <memory>
#include <string>

#include "core/progress.h"
#include "io/point_file.h"

namespace candi::io {

std::unique_ptr<PointReader> OpenPointReader(const std::string& path,
                                             const PointReadOptions& options = {});
std::unique_ptr<PointWriter> OpenPointWriter(const std::string& path, const PointWriteSpec& spec,
                                             const PointWriteOptions& options = {});

// The count and world bounds of a reader's points, from a pass over them (from where it is).
struct PointScan {
  uint64_t count = 0;
  Box3d world;
};
PointScan ScanPoints(PointReader& reader, const ProgressCallback& progress = nullptr);

// Whole-file conveniences.
PointCloud ReadPointCloud(const std::string& path, const PointReadOptions& options = {});
void WritePointCloud(const std::string& path, const PointCloud& cloud,
                     const PointWriteOptions& options = {});

}  // namespace candi::io
