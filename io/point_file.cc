#include "io/point_file.h"

#include <string>

#include "core/check.h"

namespace candi::io {

void PointReader::PrepareChunk(PointCloud* chunk) const {
  if (chunk->schema != info_.schema) {
    chunk->positions.clear();
    chunk->SetSchema(info_.schema);
  }
  chunk->frame = info_.frame;
  chunk->meta = info_.meta;
}

void CopcWriteOptions::Check() const {
  CANDI_CHECK_OPTION_GE(page_levels, 1);
  CANDI_CHECK_OPTION_GE(min_page_nodes, 0);
}

void PointWriteOptions::Check() const {
  copc.Check();
  const int v = las_version_minor, f = las_point_format;
  CANDI_CHECK_OPTION(v == -1 || (v >= 2 && v <= 4), las_version_minor, "-1, 2, 3 or 4");
  CANDI_CHECK_OPTION(f == -1 || (f >= 0 && f <= 3) || (f >= 6 && f <= 8), las_point_format,
                     "-1, 0-3 or 6-8");
  CANDI_CHECK_OPTION(!las_scale || (las_scale->minCoeff() > 0.0 && las_scale->allFinite()),
                     las_scale, "finite and > 0");
}

}  // namespace candi::io
