// candi info FILE: count, world bounds, fields, format, shift (and LAS header facts).
#include <cstdio>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/crs.h"
#include "io/point_io.h"

namespace candi::app {

namespace {

std::string TypeName(ScalarType t) { return t == ScalarType::kFloat64 ? "double" : "float"; }

std::vector<std::string> FieldList(const PointSchema& s) {
  std::vector<std::string> fields = {"x y z (" + TypeName(s.position_type) + ")"};
  if (s.colors) fields.push_back(s.alphas ? "rgba (8-bit)" : "rgb (8-bit)");
  if (s.normals) fields.push_back("normals");
  if (s.layers) fields.push_back("layer");
  for (const ScalarFieldSpec& f : s.scalars) fields.push_back(f.name + " (" + TypeName(f.type) + ")");
  return fields;
}

std::string Vec(const Eigen::Vector3d& v) {
  return FormatDouble(v.x()) + " " + FormatDouble(v.y()) + " " + FormatDouble(v.z());
}

// Positions stored as float print as the float's shortest text (0.1f, not 0.100000001490116).
std::string Coordinates(const Eigen::Vector3d& v, const io::PointFileInfo& info) {
  if (info.schema.position_type != ScalarType::kFloat32 || !info.frame.IsIdentity()) return Vec(v);
  return FormatFloat(static_cast<float>(v.x())) + " " + FormatFloat(static_cast<float>(v.y())) +
         " " + FormatFloat(static_cast<float>(v.z()));
}

// A difference of coordinates, to nine significant digits (1177.46, not 1177.4599999999627).
std::string Extent(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%.9g %.9g %.9g", v.x(), v.y(), v.z());
  return buf;
}

nlohmann::json JsonVec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

struct Scan {
  uint64_t count = 0;
  Box3d world;
  bool done = false;
};

Scan ScanPoints(io::PointReader& reader) {
  Scan scan;
  ConsoleProgressOptions options;
  ConsoleProgress progress("info: reading " + reader.path(), options);
  const uint64_t total = reader.info().count == io::kUnknownCount ? 0 : reader.info().count;
  PointCloud chunk;
  while (reader.Read(1 << 20, &chunk) > 0) {
    scan.world.Extend(chunk.WorldBounds());
    scan.count += chunk.size();
    progress.Update(scan.count, total);
  }
  scan.done = true;
  return scan;
}

nlohmann::json ToJson(const io::PointFileInfo& info, const Scan& scan, const std::string& path) {
  nlohmann::json j;
  j["file"] = path;
  j["format"] = info.description;
  j["points"] = scan.done ? scan.count : info.count;
  if (info.face_count > 0) j["faces"] = info.face_count;
  j["fields"] = FieldList(info.schema);
  j["shift"] = info.frame.IsIdentity() ? nlohmann::json(nullptr) : JsonVec(info.frame.origin);
  j["crs"] = info.meta.crs.empty() ? nlohmann::json(nullptr)
                                   : nlohmann::json({{"label", io::CrsLabel(info.meta.crs)}, {"definition", info.meta.crs}});
  if (scan.done && !scan.world.IsEmpty()) {
    j["bounds"] = {{"min", JsonVec(scan.world.min)}, {"max", JsonVec(scan.world.max)}};
  }
  if (info.header_bounds) {
    j["header_bounds"] = {{"min", JsonVec(info.header_bounds->min)}, {"max", JsonVec(info.header_bounds->max)}};
  }
  if (info.meta.las.present) {
    const LasMetadata& las = info.meta.las;
    j["las"] = {{"version", "1." + std::to_string(las.version_minor)},
                {"point_format", las.point_format},
                {"scale", JsonVec(las.scale)},
                {"offset", JsonVec(las.offset)},
                {"color_16bit", las.color_16bit},
                {"vlrs", las.vlrs.size()}};
  }
  return j;
}

void PrintText(const io::PointFileInfo& info, const Scan& scan, const std::string& path) {
  std::printf("file      %s\n", path.c_str());
  std::printf("format    %s\n", info.description.c_str());
  const uint64_t count = scan.done ? scan.count : info.count;
  if (count == io::kUnknownCount) std::printf("points    unknown (run without --no-scan)\n");
  else std::printf("points    %llu\n", static_cast<unsigned long long>(count));
  if (info.face_count > 0) std::printf("faces     %llu\n", static_cast<unsigned long long>(info.face_count));
  std::string fields;
  for (const std::string& f : FieldList(info.schema)) fields += (fields.empty() ? "" : ", ") + f;
  std::printf("fields    %s\n", fields.c_str());
  std::printf("shift     %s\n", info.frame.IsIdentity() ? "none" : (Vec(info.frame.origin) + "  (world = local + shift)").c_str());
  std::printf("crs       %s\n", info.meta.crs.empty() ? "none stated" : io::CrsLabel(info.meta.crs).c_str());
  if (scan.done && !scan.world.IsEmpty()) {
    std::printf("bounds    min %s\n          max %s\n", Coordinates(scan.world.min, info).c_str(),
                Coordinates(scan.world.max, info).c_str());
    std::printf("extent    %s\n", Extent(scan.world.Extent()).c_str());
  }
  if (info.header_bounds) {
    std::printf("header    min %s\n          max %s\n", Vec(info.header_bounds->min).c_str(),
                Vec(info.header_bounds->max).c_str());
  }
  if (info.meta.las.present) {
    const LasMetadata& las = info.meta.las;
    std::printf("las       scale %s, offset %s, %zu VLR/EVLR, colour %s\n", Vec(las.scale).c_str(),
                Vec(las.offset).c_str(), las.vlrs.size(), las.color_16bit ? "16-bit" : "8-bit values");
  }
}

}  // namespace

int RunInfo(const InfoArgs& args) {
  io::PointReadOptions options;
  options.columns = args.columns;
  auto reader = io::OpenPointReader(args.input, options);
  const io::PointFileInfo info = reader->info();
  Scan scan;
  if (!args.no_scan) scan = ScanPoints(*reader);
  // Header bounds that disagree with the points are worth a warning (a stale LAS header).
  if (scan.done && info.header_bounds && !scan.world.IsEmpty()) {
    const double tol = 1e-6 + 1e-9 * scan.world.max.cwiseAbs().maxCoeff();
    const bool inside = (scan.world.min - info.header_bounds->min).minCoeff() >= -tol &&
                        (info.header_bounds->max - scan.world.max).minCoeff() >= -tol;
    if (!inside) std::fprintf(stderr, "[warning] %s: points lie outside the header's bounds\n", args.input.c_str());
  }
  if (args.json) {
    std::printf("%s\n", ToJson(info, scan, args.input).dump(2).c_str());
  } else {
    PrintText(info, scan, args.input);
  }
  return kOk;
}

}  // namespace candi::app
