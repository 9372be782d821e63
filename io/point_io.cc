#include "io/point_io.h"

#include <memory>
#include <string>

#include "core/check.h"
#include "io/e57/e57_io.h"
#include "io/las/las_io.h"
#include "io/ply/ply_io.h"
#include "io/xyz/xyz_io.h"

namespace candi::io {

std::unique_ptr<PointReader> OpenPointReader(const std::string& path,
                                             const PointReadOptions& options) {
  options.Check();
  switch (DetectPointFormat(path)) {
    case PointFormat::kPly: return OpenPlyReader(path, options);
    case PointFormat::kLas: return OpenLasReader(path, options);
    case PointFormat::kXyz: return OpenXyzReader(path, /*pts=*/false, options);
    case PointFormat::kPts: return OpenXyzReader(path, /*pts=*/true, options);
    case PointFormat::kE57: return OpenE57Reader(path, options);
  }
  return nullptr;
}

std::unique_ptr<PointWriter> OpenPointWriter(const std::string& path, const PointWriteSpec& spec,
                                             const PointWriteOptions& options) {
  options.Check();
  switch (OutputPointFormat(path)) {
    case PointFormat::kPly: return OpenPlyWriter(path, spec, options);
    case PointFormat::kLas: return OpenLasWriter(path, spec, options);
    case PointFormat::kXyz: return OpenXyzWriter(path, /*pts=*/false, spec, options);
    case PointFormat::kPts: return OpenXyzWriter(path, /*pts=*/true, spec, options);
    case PointFormat::kE57: return OpenE57Writer(path, spec, options);
  }
  return nullptr;
}

PointCloud ReadPointCloud(const std::string& path, const PointReadOptions& options) {
  auto reader = OpenPointReader(path, options);
  PointCloud cloud;
  cloud.SetSchema(reader->info().schema);
  cloud.frame = reader->info().frame;
  cloud.meta = reader->info().meta;
  if (reader->info().count != kUnknownCount) cloud.Reserve(reader->info().count);
  PointCloud chunk;
  while (reader->Read(1 << 20, &chunk) > 0) cloud.Append(chunk);
  return cloud;
}

void WritePointCloud(const std::string& path, const PointCloud& cloud,
                     const PointWriteOptions& options) {
  cloud.CheckConsistent();
  PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, cloud.size()};
  auto writer = OpenPointWriter(path, spec, options);
  writer->Write(cloud);
  writer->Close();
}

PointScan ScanPoints(PointReader& reader, const ProgressCallback& progress) {
  PointScan scan;
  const uint64_t total = reader.info().count == kUnknownCount ? 0 : reader.info().count;
  PointCloud chunk;
  while (reader.Read(1 << 20, &chunk) > 0) {
    scan.world.Extend(chunk.WorldBounds());
    scan.count += chunk.size();
    if (progress) progress(scan.count, total);
  }
  return scan;
}

}  // namespace candi::io
