#include "io/point_file.h"

#include <stdexcept>
#include <string>

namespace candi::io {

void PointReader::PrepareChunk(PointCloud* chunk) const {
  if (chunk->schema != info_.schema) {
    chunk->positions.clear();
    chunk->SetSchema(info_.schema);
  }
  chunk->frame = info_.frame;
  chunk->meta = info_.meta;
}

void PointWriteOptions::Check() const {
  if (las_version_minor != -1 && (las_version_minor < 2 || las_version_minor > 4)) {
    throw std::invalid_argument("PointWriteOptions::las_version_minor = " +
                                std::to_string(las_version_minor) + "; must be -1, 2, 3 or 4");
  }
  const int f = las_point_format;
  if (f != -1 && !((f >= 0 && f <= 3) || (f >= 6 && f <= 8))) {
    throw std::invalid_argument("PointWriteOptions::las_point_format = " + std::to_string(f) +
                                "; must be -1, 0-3 or 6-8");
  }
  if (las_scale && !(las_scale->minCoeff() > 0.0 && las_scale->allFinite())) {
    throw std::invalid_argument("PointWriteOptions::las_scale must be finite and > 0");
  }
}

}  // namespace candi::io
