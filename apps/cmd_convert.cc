// candi convert IN OUT: streams points from one format to another, choosing the output shift.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/crs.h"
#include "io/point_io.h"

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

io::PointWriteOptions WriteOptions(const ConvertArgs& args) {
  io::PointWriteOptions o;
  o.ply_encoding = args.ply_encoding == "ascii"       ? io::PlyEncoding::kAscii
                   : args.ply_encoding == "binary_be" ? io::PlyEncoding::kBinaryBigEndian
                                                      : io::PlyEncoding::kBinaryLittleEndian;
  o.precision = args.precision == "float"    ? io::PositionPrecision::kFloat32
                : args.precision == "double" ? io::PositionPrecision::kFloat64
                                             : io::PositionPrecision::kAuto;
  o.las_point_format = args.las_format;
  o.las_version_minor = args.las_version;
  if (!args.las_scale.empty()) o.las_scale = ParseScale(args.las_scale);
  o.columns = args.out_columns;
  o.Check();
  return o;
}

// The output frame: kept, none, explicit, or automatic from the header bounds or the first chunk.
// With a reprojection the header's bounds are in the old CRS: the first chunk's count.
LocalFrame OutputFrame(const ConvertArgs& args, const io::PointReader& reader, const PointCloud& first) {
  const bool reprojected = !args.to_crs.empty();
  if (args.shift.empty()) return reprojected ? LocalFrame{} : reader.info().frame;
  if (args.shift == "none") return LocalFrame{};
  if (args.shift != "auto") return ParseShift(args.shift);
  const Box3d box = reader.info().header_bounds && !reprojected ? *reader.info().header_bounds : first.WorldBounds();
  return LocalFrame::Auto(box);
}

// The input's CRS: the file's, or --crs for a file that states none (a different one is an error).
std::string InputCrs(const ConvertArgs& args, const io::PointFileInfo& info) {
  const std::string& stated = info.meta.crs;
  if (args.crs.empty()) return stated;
  io::DescribeCrs(args.crs, "--crs");
  if (!stated.empty() && !io::SameCrs(stated, args.crs)) {
    throw InputError(args.input, "", "states " + io::CrsLabel(stated) + " but --crs says " + io::CrsLabel(args.crs) +
                                         "; to reproject, use --to-crs");
  }
  return args.crs;
}

// Reprojection drops what stated the old CRS and the LAS scale/offset chosen for it (a scale of
// 0.01 in metres means 1 km in degrees): the writer chooses them anew, 1e-7 degrees (~1 cm) for a
// geographic CRS.
void PrepareReprojection(const ConvertArgs& args, io::PointWriteSpec* spec, io::PointWriteOptions* options) {
  LasMetadata& las = spec->meta.las;
  las.vlrs.erase(std::remove_if(las.vlrs.begin(), las.vlrs.end(),
                                [](const LasVlr& v) { return v.user_id == "LASF_Projection" || (v.user_id == "liblas" && v.record_id == 2112); }),
                 las.vlrs.end());
  las.present = false;
  spec->meta.crs = args.to_crs;
  if (!options->las_scale && io::DescribeCrs(args.to_crs, "--to-crs").geographic) {
    options->las_scale = Eigen::Vector3d(1e-7, 1e-7, 0.001);
  }
}

void Reproject(const io::CrsTransform& transform, PointCloud* chunk) {
  for (Eigen::Vector3d& p : chunk->positions) p = chunk->frame.ToWorld(p);
  chunk->frame = LocalFrame();
  transform.Apply(&chunk->positions);
}

}  // namespace

int RunConvert(const ConvertArgs& args) {
  io::PointWriteOptions write_options = WriteOptions(args);
  if (!args.shift.empty() && args.shift != "auto" && args.shift != "none") ParseShift(args.shift);
  io::OutputPointFormat(args.output);  // an unknown output extension fails before any reading
  io::PointReadOptions read_options;
  read_options.columns = args.columns;
  auto reader = io::OpenPointReader(args.input, read_options);
  constexpr size_t kChunk = 1 << 20;
  PointCloud chunk;
  size_t got = reader->Read(kChunk, &chunk);
  io::PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  spec.meta.crs = InputCrs(args, reader->info());
  spec.count = reader->info().count;
  std::unique_ptr<io::CrsTransform> transform;
  if (!args.to_crs.empty()) {
    if (spec.meta.crs.empty()) {
      throw InputError(args.input, "", "states no CRS to reproject from; give it with --crs");
    }
    transform = std::make_unique<io::CrsTransform>(spec.meta.crs, args.to_crs, args.input);
    const std::string from = io::CrsLabel(spec.meta.crs);
    PrepareReprojection(args, &spec, &write_options);
    Reproject(*transform, &chunk);
    LogInfo(from + " -> " + io::CrsLabel(args.to_crs) + " with PROJ (" + transform->operation() + ")");
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
  auto writer = io::OpenPointWriter(args.output, spec, write_options);
  ConsoleProgress progress("convert " + args.input + " -> " + args.output);
  const uint64_t total = spec.count == io::kUnknownCount ? 0 : spec.count;
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
