// Several layers' point clouds (one schema, e.g. from SampleSurface with `layer` set) written as
// one point file: the clouds go through one writer in turn, in the first cloud's frame (the
// others are re-expressed, exactly as PointCloud::Append would), so no merged copy of the points
// is made. The file gets the comment "candi_layers 0=<name 0> 1=<name 1> ...".
// Failures: as WritePointCloud (InputError naming the path; the destination is left as it was).
// ReadLayerNames reads that comment back.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "io/point_io.h"

namespace candi::io {

void WriteLayerClouds(const std::string& path, const std::vector<PointCloud>& clouds,
                      const std::vector<std::string>& names, const PointWriteOptions& options = {});

// The layer names of a file's "candi_layers 0=A 1=B" comment, by layer id (empty without one;
// malformed items are skipped).
std::map<int, std::string> ReadLayerNames(const PointCloudMeta& meta);

}  // namespace candi::io
