// candi convert IN OUT: streams points from one format to another, choosing the output shift.
#include <cmath>
#include <stdexcept>

#include "apps/arg_parse.h"
#include "apps/commands.h"
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
LocalFrame OutputFrame(const ConvertArgs& args, const PointReader& reader, const PointCloud& first) {
  if (args.shift.empty()) return reader.info().frame;
  if (args.shift == "none") return LocalFrame{};
  if (args.shift != "auto") return ParseShift(args.shift);
  const Box3d box = reader.info().header_bounds ? *reader.info().header_bounds : first.WorldBounds();
  return LocalFrame::Auto(box);
}

}  // namespace

int RunConvert(const ConvertArgs& args) {
  const PointWriteOptions write_options = WriteOptions(args);
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
  spec.count = reader->info().count;
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
  }
  writer->Close();
  progress.Finish();
  return kOk;
}

}  // namespace candi::app
