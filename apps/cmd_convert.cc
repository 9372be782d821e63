// candi convert IN OUT: streams points from one format to another, choosing the output shift.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "core/crs.h"
#include "core/log.h"
#include "core/point_io.h"
#include "core/progress.h"

namespace candi::app {

namespace {

Eigen::Vector3d ParseScale(const std::string& text) {
  const std::vector<double> v = ParseNumbers(text, ',', "--las-scale");
  for (double s : v) {
    if (!(s > 0)) throw std::invalid_argument("--las-scale '" + text + "': each scale must be > 0");
  }
  if (v.size() == 1) return Eigen::Vector3d::Constant(v[0]);
  if (v.size() == 3) return Eigen::Vector3d(v[0], v[1], v[2]);
  throw std::invalid_argument("--las-scale '" + text + "': expected s or sx,sy,sz");
}

PointWriteOptions WriteOptions(const ConvertArgs& args) {
  PointWriteOptions o;
  o.ply_encoding = args.ply_encoding == "ascii"       ? PlyEncoding::kAscii
                   : args.ply_encoding == "binary_be" ? PlyEncoding::kBinaryBigEndian
                                                      : PlyEncoding::kBinaryLittleEndian;
  o.precision = args.precision == "float"    ? PositionPrecision::kFloat32
                : args.precision == "double" ? PositionPrecision::kFloat64
                                             : PositionPrecision::kAuto;
  o.las_point_format = args.las_format;
  o.las_version_minor = args.las_version;
  if (!args.las_scale.empty()) o.las_scale = ParseScale(args.las_scale);
  o.columns = args.out_columns;
  o.Check();
  return o;
}

// The output frame: kept, none, explicit, or automatic from the header bounds or the first chunk.
// With a reprojection the header's bounds are in the old CRS: the first chunk's count.
LocalFrame OutputFrame(const ConvertArgs& args, const PointReader& reader, const PointCloud& first) {
  const bool reprojected = !args.to_crs.empty();
  if (args.shift.empty()) return reprojected ? LocalFrame{} : reader.info().frame;
  if (args.shift == "none") return LocalFrame{};
  if (args.shift != "auto") return ParseShift(args.shift);
  const Box3d box = reader.info().header_bounds && !reprojected ? *reader.info().header_bounds : first.WorldBounds();
  return LocalFrame::Auto(box);
}

// The input's CRS: the file's, or --crs for a file that states none (a different one is an error).
std::string InputCrs(const ConvertArgs& args, const PointFileInfo& info) {
  const std::string& stated = info.meta.crs;
  if (args.crs.empty()) return stated;
  DescribeCrs(args.crs, "--crs");
  if (!stated.empty() && !SameCrs(stated, args.crs)) {
    throw InputError(args.input, "", "states " + CrsLabel(stated) + " but --crs says " + CrsLabel(args.crs) +
                                         "; to reproject, use --to-crs");
  }
  return args.crs;
}

// Reprojection drops what stated the old CRS and the LAS scale/offset chosen for it (a scale of
// 0.01 in metres means 1 km in degrees): the writer chooses them anew, 1e-7 degrees (~1 cm) for a
// geographic CRS.
void PrepareReprojection(const ConvertArgs& args, PointWriteSpec* spec, PointWriteOptions* options) {
  LasMetadata& las = spec->meta.las;
  las.vlrs.erase(std::remove_if(las.vlrs.begin(), las.vlrs.end(),
                                [](const LasVlr& v) { return v.user_id == "LASF_Projection" || (v.user_id == "liblas" && v.record_id == 2112); }),
                 las.vlrs.end());
  las.present = false;
  spec->meta.crs = args.to_crs;
  if (!options->las_scale && DescribeCrs(args.to_crs, "--to-crs").geographic) {
    options->las_scale = Eigen::Vector3d(1e-7, 1e-7, 0.001);
  }
}

void Reproject(const CrsTransform& transform, PointCloud* chunk) {
  for (Eigen::Vector3d& p : chunk->positions) p = chunk->frame.ToWorld(p);
  chunk->frame = LocalFrame();
  transform.Apply(&chunk->positions);
}

}  // namespace

int RunConvert(const ConvertArgs& args) {
  PointWriteOptions write_options = WriteOptions(args);
  if (!args.shift.empty() && args.shift != "auto" && args.shift != "none") ParseShift(args.shift);
  OutputPointFormat(args.output);  // an unknown output extension fails before any reading
  PointReadOptions read_options;
  read_options.columns = args.columns;
  auto reader = OpenPointReader(args.input, read_options);
  constexpr size_t kChunk = 1 << 20;
  PointCloud chunk;
  size_t got = reader->Read(kChunk, &chunk);
  PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  spec.meta.crs = InputCrs(args, reader->info());
  spec.count = reader->info().count;
  std::unique_ptr<CrsTransform> transform;
  if (!args.to_crs.empty()) {
    if (spec.meta.crs.empty()) {
      throw InputError(args.input, "", "states no CRS to reproject from; give it with --crs");
    }
    transform = std::make_unique<CrsTransform>(spec.meta.crs, args.to_crs, args.input);
    const std::string from = CrsLabel(spec.meta.crs);
    PrepareReprojection(args, &spec, &write_options);
    Reproject(*transform, &chunk);
    LogInfo(from + " -> " + CrsLabel(args.to_crs) + " with PROJ (" + transform->operation() + ")");
  }
  spec.frame = OutputFrame(args, *reader, chunk);
  if (spec.frame != reader->info().frame) {
    LogInfo("output shift: " + (spec.frame.IsIdentity() ? std::string("none") : spec.frame.ToString()) +
            " (world = local + shift)");
  }
  if (reader->info().face_count > 0) {
    LogWarning(args.input + " has " + std::to_string(reader->info().face_count) +
               " faces; convert writes the vertices as points, without the faces");
  }
  auto writer = OpenPointWriter(args.output, spec, write_options);
  ConsoleProgress progress("convert " + args.input + " -> " + args.output);
  const uint64_t total = spec.count == kUnknownCount ? 0 : spec.count;
  uint64_t done = 0;
  while (got > 0) {
    writer->Write(chunk);
    done += got;
    progress.Update(done, total);
    got = reader->Read(kChunk, &chunk);
    if (transform) Reproject(*transform, &chunk);
  }
  writer->Close();
  progress.Finish();
  return kOk;
}

}  // namespace candi::app
