#include "io/convert.h"

#include <algorithm>
#include <memory>
#include <stdexcept>

#include "core/check.h"
#include "core/log.h"
#include "io/crs.h"
#include "io/point_io.h"

namespace candi::io {

namespace {

constexpr size_t kChunk = 1 << 20;

// The output frame: kept, none, given, or automatic from the header bounds or the first chunk.
// With a reprojection the header's bounds are in the old CRS: the first chunk's count.
LocalFrame OutputFrame(const ConvertOptions& o, const PointReader& reader, const PointCloud& first) {
  const bool reprojected = !o.to_crs.empty();
  switch (o.shift) {
    case ShiftChoice::kKeep: return reprojected ? LocalFrame{} : reader.info().frame;
    case ShiftChoice::kNone: return LocalFrame{};
    case ShiftChoice::kGiven: return o.given_shift;
    case ShiftChoice::kAuto: break;
  }
  const Box3d box = reader.info().header_bounds && !reprojected ? *reader.info().header_bounds : first.WorldBounds();
  return LocalFrame::Auto(box);
}

// The input's CRS: the file's, or options.crs for a file that states none (a different one is an
// error).
std::string InputCrs(const ConvertOptions& o, const std::string& input, const PointFileInfo& info) {
  const std::string& stated = info.meta.crs;
  if (o.crs.empty()) return stated;
  DescribeCrs(o.crs, "--crs");
  if (!stated.empty() && !SameCrs(stated, o.crs)) {
    throw InputError(input, "", "states " + CrsLabel(stated) + " but --crs says " + CrsLabel(o.crs) +
                                    "; to reproject, use --to-crs");
  }
  return o.crs;
}

// Reprojection drops what stated the old CRS and the LAS scale/offset chosen for it (a scale of
// 0.01 in metres means 1 km in degrees): the writer chooses them anew, 1e-7 degrees (~1 cm) for a
// geographic CRS.
void PrepareReprojection(const ConvertOptions& o, PointWriteSpec* spec, PointWriteOptions* write) {
  LasMetadata& las = spec->meta.las;
  las.vlrs.erase(std::remove_if(las.vlrs.begin(), las.vlrs.end(),
                                [](const LasVlr& v) {
                                  return v.user_id == "LASF_Projection" || (v.user_id == "liblas" && v.record_id == 2112);
                                }),
                 las.vlrs.end());
  las.present = false;
  spec->meta.crs = o.to_crs;
  if (!write->las_scale && DescribeCrs(o.to_crs, "--to-crs").geographic) {
    write->las_scale = Eigen::Vector3d(1e-7, 1e-7, 0.001);
  }
}

void Reproject(const CrsTransform& transform, PointCloud* chunk) {
  for (Eigen::Vector3d& p : chunk->positions) p = chunk->frame.ToWorld(p);
  chunk->frame = LocalFrame();
  transform.Apply(&chunk->positions);
}

}  // namespace

void ConvertOptions::Check() const { write.Check(); }

ConvertSummary ConvertPointFile(const ConvertOptions& options, const std::string& input, const std::string& output,
                                const ProgressCallback& progress) {
  options.Check();
  PointWriteOptions write = options.write;
  OutputPointFormat(output);  // an unknown output extension fails before any reading
  auto reader = OpenPointReader(input, options.read);
  PointCloud chunk;
  size_t got = reader->Read(kChunk, &chunk);
  PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  spec.meta.crs = InputCrs(options, input, reader->info());
  spec.count = reader->info().count;
  std::unique_ptr<CrsTransform> transform;
  if (!options.to_crs.empty()) {
    if (spec.meta.crs.empty()) throw InputError(input, "", "states no CRS to reproject from; give it with --crs");
    transform = std::make_unique<CrsTransform>(spec.meta.crs, options.to_crs, input);
    const std::string from = CrsLabel(spec.meta.crs);
    PrepareReprojection(options, &spec, &write);
    Reproject(*transform, &chunk);
    LogInfo(from + " -> " + CrsLabel(options.to_crs) + " with PROJ (" + transform->operation() + ")");
  }
  spec.frame = OutputFrame(options, *reader, chunk);
  if (spec.frame != reader->info().frame) {
    LogInfo("output shift: " + (spec.frame.IsIdentity() ? std::string("none") : spec.frame.ToString()) +
            " (world = local + shift)");
  }
  if (reader->info().face_count > 0) {
    LogWarning(input + " has " + std::to_string(reader->info().face_count) +
               " faces; convert writes the vertices as points, without the faces");
  }
  auto writer = OpenPointWriter(output, spec, write);
  const uint64_t total = spec.count == kUnknownCount ? 0 : spec.count;
  if (progress) progress(0, total);
  ConvertSummary summary;
  summary.frame = spec.frame;
  while (got > 0) {
    writer->Write(chunk);
    summary.points += got;
    if (progress) progress(summary.points, total);
    got = reader->Read(kChunk, &chunk);
    if (transform) Reproject(*transform, &chunk);
  }
  writer->Close();
  return summary;
}

}  // namespace candi::io
