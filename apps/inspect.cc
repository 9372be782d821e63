// candi info, candi convert, candi compare: a point file's count, bounds, fields, format, shift and
// CRS; a point file in another format, shift or CRS (io/convert.h); the deviation of one cloud from
// a reference cloud or mesh (pipeline/compare.h).
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/convert.h"
#include "io/copc/copc_read.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "pipeline/compare.h"

namespace candi::apps {

namespace {

struct InfoArgs {
  std::string input;
  io::PointReadOptions read;
  bool json = false;     // machine-readable output
  bool no_scan = false;  // header only: skip the pass over the points
};

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
  return FormatFloat(static_cast<float>(v.x())) + " " + FormatFloat(static_cast<float>(v.y())) + " " +
         FormatFloat(static_cast<float>(v.z()));
}

// A difference of coordinates, to nine significant digits (1177.46, not 1177.4599999999627).
std::string Extent(const Eigen::Vector3d& v) {
  char buf[96];
  std::snprintf(buf, sizeof(buf), "%.9g %.9g %.9g", v.x(), v.y(), v.z());
  return buf;
}

nlohmann::json JsonVec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

std::string Counts(const std::vector<uint64_t>& v) {
  std::string text;
  for (uint64_t c : v) text += (text.empty() ? "" : " ") + std::to_string(c);
  return text;
}

nlohmann::json ToJson(const io::PointFileInfo& info, const io::PointScan* scan, const std::optional<io::CopcSummary>& copc,
                      const std::string& path) {
  nlohmann::json j;
  j["file"] = path;
  j["format"] = info.description;
  j["points"] = scan ? scan->count : info.count;
  if (info.face_count > 0) j["faces"] = info.face_count;
  j["fields"] = FieldList(info.schema);
  j["shift"] = info.frame.IsIdentity() ? nlohmann::json(nullptr) : JsonVec(info.frame.origin);
  j["crs"] = info.meta.crs.empty()
                 ? nlohmann::json(nullptr)
                 : nlohmann::json({{"label", io::CrsLabel(info.meta.crs)}, {"definition", info.meta.crs}});
  if (scan && !scan->world.IsEmpty()) {
    j["bounds"] = {{"min", JsonVec(scan->world.min)}, {"max", JsonVec(scan->world.max)}};
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
  if (copc) {
    j["copc"] = {{"center", JsonVec(copc->info.center)},
                 {"halfsize", copc->info.halfsize},
                 {"spacing", copc->info.spacing},
                 {"gps_time", {copc->info.gpstime_minimum, copc->info.gpstime_maximum}},
                 {"pages", copc->pages},
                 {"nodes", copc->nodes},
                 {"empty_nodes", copc->empty_nodes},
                 {"points", copc->points},
                 {"nodes_by_level", copc->nodes_by_level},
                 {"points_by_level", copc->points_by_level}};
  }
  return j;
}

void PrintText(const io::PointFileInfo& info, const io::PointScan* scan, const std::optional<io::CopcSummary>& copc,
               const std::string& path) {
  std::printf("file      %s\n", path.c_str());
  std::printf("format    %s\n", info.description.c_str());
  const uint64_t count = scan ? scan->count : info.count;
  if (count == io::kUnknownCount) std::printf("points    unknown (run without --no-scan)\n");
  else std::printf("points    %llu\n", static_cast<unsigned long long>(count));
  if (info.face_count > 0) std::printf("faces     %llu\n", static_cast<unsigned long long>(info.face_count));
  std::string fields;
  for (const std::string& f : FieldList(info.schema)) fields += (fields.empty() ? "" : ", ") + f;
  std::printf("fields    %s\n", fields.c_str());
  std::printf("shift     %s\n",
              info.frame.IsIdentity() ? "none" : (Vec(info.frame.origin) + "  (world = local + shift)").c_str());
  std::printf("crs       %s\n", info.meta.crs.empty() ? "none stated" : io::CrsLabel(info.meta.crs).c_str());
  if (scan && !scan->world.IsEmpty()) {
    std::printf("bounds    min %s\n          max %s\n", Coordinates(scan->world.min, info).c_str(),
                Coordinates(scan->world.max, info).c_str());
    std::printf("extent    %s\n", Extent(scan->world.Extent()).c_str());
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
  if (copc) {
    std::printf("copc      COPC 1.0: %llu nodes (%llu empty) in %llu hierarchy page(s), levels 0-%zu, root spacing %s m; "
                "cube centre %s, half-width %s\n",
                static_cast<unsigned long long>(copc->nodes), static_cast<unsigned long long>(copc->empty_nodes),
                static_cast<unsigned long long>(copc->pages),
                copc->nodes_by_level.empty() ? size_t{0} : copc->nodes_by_level.size() - 1,
                FormatSignificant(copc->info.spacing, 6).c_str(),
                (FormatSignificant(copc->info.center.x(), 10) + " " + FormatSignificant(copc->info.center.y(), 10) +
                 " " + FormatSignificant(copc->info.center.z(), 10)).c_str(),
                FormatSignificant(copc->info.halfsize, 10).c_str());
    std::printf("          nodes by level %s\n          points by level %s\n", Counts(copc->nodes_by_level).c_str(),
                Counts(copc->points_by_level).c_str());
  }
}

int RunInfo(const InfoArgs& args) {
  auto reader = io::OpenPointReader(args.input, args.read);
  const io::PointFileInfo info = reader->info();
  std::optional<io::PointScan> scan;
  if (!args.no_scan) {
    ConsoleProgress progress("info: reading " + reader->path());
    scan = io::ScanPoints(*reader, progress.Callback());
  }
  // Header bounds that disagree with the points are worth a warning (a stale LAS header).
  if (scan && info.header_bounds && !scan->world.IsEmpty()) {
    const double tol = 1e-6 + 1e-9 * scan->world.max.cwiseAbs().maxCoeff();
    const bool inside = (scan->world.min - info.header_bounds->min).minCoeff() >= -tol &&
                        (info.header_bounds->max - scan->world.max).minCoeff() >= -tol;
    if (!inside) std::fprintf(stderr, "[warning] %s: points lie outside the header's bounds\n", args.input.c_str());
  }
  const io::PointScan* scanned = scan ? &*scan : nullptr;
  // A COPC file's hierarchy, as COPC readers walk it; its counts must add up to the points. A
  // malformed one is a warning: the points read as LAZ all the same (a LAS file may carry a copc
  // VLR that a conversion forwarded).
  std::optional<io::CopcSummary> copc;
  try {
    if (info.meta.las.present) copc = io::ReadCopcSummary(reader->path(), info.meta.las);
  } catch (const InputError& e) {
    std::fprintf(stderr, "[warning] not a valid COPC hierarchy: %s\n", e.what());
  }
  const uint64_t count = scan ? scan->count : info.count;
  if (copc && count != io::kUnknownCount && copc->points != count) {
    std::fprintf(stderr, "[warning] %s: the COPC hierarchy's nodes hold %llu points, the file %llu\n",
                 args.input.c_str(), static_cast<unsigned long long>(copc->points),
                 static_cast<unsigned long long>(count));
  }
  if (args.json) {
    std::printf("%s\n", ToJson(info, scanned, copc, args.input).dump(2).c_str());
  } else {
    PrintText(info, scanned, copc, args.input);
  }
  return kOk;
}

void AddInfo(Command& root) {
  InfoArgs& a = root.Keep<InfoArgs>();
  Command c = root.Add("info", "Print a point file's count, bounds (world), fields, format (LAZ: its compressor), shift "
                               "and CRS, and a COPC file's hierarchy (nodes and points by level)");
  c.Option("file", a.input, "Point file (.ply .las .laz .e57 .xyz .txt .pts)").Required();
  c.Option("--columns", a.read.columns, "XYZ/PTS column spec, e.g. x,y,z,r,g,b");
  c.Flag("--json", a.json, "Print JSON instead of text");
  c.Flag("--no-scan", a.no_scan, "Header only: do not read the points (bounds from the header)");
  c.Run([&a] { return RunInfo(a); });
  c.Footer("Example: candi info site.las");
}

struct ConvertArgs {
  std::string input, output;
  io::ConvertOptions options;
  std::string shift;      // "" (keep the input's), "auto", "none" or "x,y,z"
  std::string las_scale;  // "s" or "sx,sy,sz"
  double copc_memory_mb = 0;
};

Eigen::Vector3d ParseScale(const std::string& text) {
  const std::vector<double> v = ParseNumbers(text, ',', "--las-scale");
  for (double s : v) {
    if (!(s > 0)) throw std::invalid_argument("--las-scale '" + text + "': each scale must be > 0");
  }
  if (v.size() == 1) return Eigen::Vector3d::Constant(v[0]);
  if (v.size() == 3) return Eigen::Vector3d(v[0], v[1], v[2]);
  throw std::invalid_argument("--las-scale '" + text + "': expected s or sx,sy,sz");
}

int RunConvert(const ConvertArgs& args) {
  io::ConvertOptions o = args.options;
  if (!args.las_scale.empty()) o.write.las_scale = ParseScale(args.las_scale);
  o.write.copc.memory_bytes = CopcMemoryBytes(args.copc_memory_mb);
  if (args.shift == "auto") {
    o.shift = io::ShiftChoice::kAuto;
  } else if (args.shift == "none") {
    o.shift = io::ShiftChoice::kNone;
  } else if (!args.shift.empty()) {
    o.shift = io::ShiftChoice::kGiven;
    o.given_shift = ParseShift(args.shift);
  }
  // The bar starts when the output is open (the call's first report), so that a file that fails
  // to open prints only its error.
  std::optional<ConsoleProgress> progress;
  // What the writer does once every point is in (a COPC file's octree and chunks): a bar a stage.
  StagedProgress stages("convert " + args.output);
  o.write.close_progress = [&](const std::string& stage, uint64_t done, uint64_t total) {
    if (progress) progress->Finish();
    stages.Update(stage, done, total);
  };
  io::ConvertPointFile(o, args.input, args.output, [&](uint64_t done, uint64_t total) {
    if (!progress) progress.emplace("convert " + args.input + " -> " + args.output);
    if (done > 0) progress->Update(done, total);
  });
  stages.Finish();
  if (progress) progress->Finish();
  return kOk;
}

}  // namespace

void AddCopcMemory(Command& c, double& mb) {
  c.Option("--copc-memory", mb,
           "COPC output: the memory (MB) its records may take until the file is complete; "
           "beyond it they are spilled beside the file (default 0: half of this machine's)");
}

uint64_t CopcMemoryBytes(double mb) {
  if (!(mb >= 0)) {
    throw std::invalid_argument("--copc-memory " + FormatSignificant(mb, 6) +
                                ": must be >= 0 (MB; 0: half of this machine's memory)");
  }
  return static_cast<uint64_t>(mb * 1048576.0);
}

namespace {

void AddConvert(Command& root) {
  ConvertArgs& a = root.Keep<ConvertArgs>();
  io::ConvertOptions& o = a.options;
  Command c = root.Add("convert", "Convert between PLY, LAS, LAZ, COPC, E57, XYZ and PTS, streaming; reproject "
                                  "with PROJ");
  c.Option("input", a.input, "Input point file").Required();
  c.Option("output", a.output, "Output point file; format from its extension").Required();
  c.Option("--shift", a.shift,
           "Output origin shift: auto (rounded centre when coordinates exceed 1e4 m), none, "
           "or x,y,z; default: keep the input's");
  c.Option("--columns", o.read.columns, "Input XYZ/PTS column spec, e.g. x,y,z,r,g,b");
  c.Option("--out-columns", o.write.columns, "Output XYZ/PTS column spec");
  c.Choice("--ply-encoding", o.write.ply_encoding,
           {{"binary", io::PlyEncoding::kBinaryLittleEndian},
            {"binary_be", io::PlyEncoding::kBinaryBigEndian},
            {"ascii", io::PlyEncoding::kAscii}},
           "PLY output: binary, binary_be or ascii");
  c.Choice("--precision", o.write.precision,
           {{"auto", io::PositionPrecision::kAuto},
            {"float", io::PositionPrecision::kFloat32},
            {"double", io::PositionPrecision::kFloat64}},
           "PLY/XYZ positions: auto, float or double");
  c.Option("--las-scale", a.las_scale, "LAS output scale, s or sx,sy,sz (default: keep, else 0.001)");
  c.Option("--las-format", o.write.las_point_format,
           "LAS/LAZ output point format: 0-3 or 6-8 (COPC holds 6-8: 0/1 are written as 6, 2/3 as 7)");
  c.Option("--las-version", o.write.las_version_minor,
           "LAS/LAZ output minor version: 2, 3 or 4 (COPC is always LAS 1.4)");
  AddCopcMemory(c, a.copc_memory_mb);
  c.Option("--crs", o.crs, "The input's CRS (e.g. EPSG:4979), for files that state none; carried into the output");
  c.Option("--to-crs", o.to_crs, "Reproject into this CRS with PROJ (e.g. EPSG:32749)");
  c.Run([&a] { return RunConvert(a); });
  c.Footer("Examples: candi convert scan.las scan.ply --shift auto\n"
           "          candi convert gnss_wgs84.laz site_utm.las --to-crs EPSG:32749\n"
           "          candi convert scan.ply scan.laz --las-format 7\n"
           "          candi convert scan.las scan.copc.laz   (for Potree, QGIS, CloudCompare)");
}

struct CompareArgs {
  std::string reference, compared, output;
  pipeline::CompareOptions options;
};

int RunCompare(const CompareArgs& args) {
  std::optional<ConsoleProgress> progress;
  const pipeline::CompareOutcome out = pipeline::RunCompare(
      args.options, args.reference, args.compared, args.output, [&](uint64_t done, uint64_t total) {
        if (!progress) progress.emplace(compare::MethodName(args.options.deviation.method) + " " +
                                        args.compared);
        progress->Update(done, total);
      });
  if (progress) progress->Finish();
  const compare::DeviationSummary& s = out.summary;
  auto mm = [](double m) { return std::isnan(m) ? std::string("n/a") : FormatSignificant(m * 1000, 5) + " mm"; };
  std::printf("%-22s %s\n", "method", compare::MethodName(s.method).c_str());
  std::printf("%-22s %llu (%llu undefined)\n", "points",
              static_cast<unsigned long long>(s.count), static_cast<unsigned long long>(s.undefined));
  std::printf("%-22s %s\n", "mean", mm(s.mean).c_str());
  std::printf("%-22s %s\n", "std", mm(s.std).c_str());
  std::printf("%-22s %s\n", "rms", mm(s.rms).c_str());
  if (!s.percentiles.empty()) {
    std::printf("%-22s %s / %s / %s\n", "p5 / median / p95", mm(s.percentiles[1].second).c_str(),
                mm(s.percentiles[3].second).c_str(), mm(s.percentiles[5].second).c_str());
  }
  std::printf("%-22s %s\n", ("within " + mm(s.tolerance)).c_str(),
              s.defined ? (FormatSignificant(100 * s.within_tolerance, 4) + " %").c_str() : "n/a");
  if (s.method == compare::Method::kM3C2) {
    std::printf("%-22s %llu\n", "significant change", static_cast<unsigned long long>(s.significant));
  }
  for (const std::string& w : out.result.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  std::printf("wrote %s, %s, %s, %s\n", out.cloud.c_str(), out.json.c_str(), out.histogram.c_str(),
              out.report.c_str());
  return kOk;
}

void AddCompare(Command& root) {
  CompareArgs& a = root.Keep<CompareArgs>();
  compare::DeviationOptions& d = a.options.deviation;
  Command c = root.Add("compare", "Deviation of COMPARED from REFERENCE (C2C, C2M, M3C2, as CloudCompare): the "
                                  "distance per point as a scalar field, a summary, a histogram and a report");
  c.Option("reference", a.reference, "Reference point file (C2C, M3C2) or mesh, PLY or OBJ (C2M)").Required();
  c.Option("compared", a.compared, "Compared point file: one distance per point, in its order").Required();
  c.Option("-o,--output", a.output,
           "Output point file (format by extension; PLY and LAS keep the fields); also writes "
           "OUT.compare.json, OUT.histogram.svg and OUT.report.md").Required();
  c.Choice("--method", d.method,
           {{"c2c", compare::Method::kC2C}, {"c2m", compare::Method::kC2M}, {"m3c2", compare::Method::kM3C2}},
           "c2c (nearest point), c2m (signed, to a mesh) or m3c2 (Lague et al. 2013)");
  c.Choice("--model", d.c2c.local_model,
           {{"none", compare::LocalModel::kNone}, {"plane", compare::LocalModel::kPlane},
            {"quadric", compare::LocalModel::kQuadric}},
           "C2C: a local model of the reference: none, plane or quadric (least squares)");
  c.Option("--model-neighbours", d.c2c.model_neighbours, "C2C: reference points a local model is fitted to");
  c.FlagOff("--unsigned", d.c2m.signed_distance, "C2M: |distance| instead of the signed distance");
  c.Option("--normal-scale", d.m3c2.normal_scale, "M3C2: D, the diameter normals are fitted over, m (0: 2 d)");
  c.Option("--projection-scale", d.m3c2.projection_scale,
           "M3C2: d, the cylinder's diameter, m (0: ~30 reference points in it)");
  c.Option("--max-depth", d.m3c2.max_depth, "M3C2: the cylinder's half-length, m (0: D)");
  c.Option("--registration-error", d.m3c2.registration_error, "M3C2: added to LoD95, m");
  c.Option("--min-points", d.m3c2.min_points, "M3C2: points each cloud needs in a cylinder");
  c.Choice("--orientation", d.m3c2.orientation,
           {{"+z", compare::NormalOrientation::kPlusZ}, {"-z", compare::NormalOrientation::kMinusZ},
            {"+x", compare::NormalOrientation::kPlusX}, {"-x", compare::NormalOrientation::kMinusX},
            {"+y", compare::NormalOrientation::kPlusY}, {"-y", compare::NormalOrientation::kMinusY},
            {"out", compare::NormalOrientation::kOutward}},
           "M3C2: normals towards +z (... -y), or out: away from the reference's centroid");
  c.Option("--tolerance", a.options.summary.tolerance, "Summary: |distance| within this counts as within, m");
  c.Option("--bins", a.options.summary.bins, "Histogram bins");
  c.Option("--range", a.options.summary.range, "Histogram range, m (signed: -range..range; 0: the 99th percentile)");
  c.Option("--columns", a.options.columns, "XYZ/PTS column spec of text inputs, e.g. x,y,z,r,g,b");
  c.Option("--threads", d.threads, "Threads (0: all); results do not depend on it").Range(0, 256);
  c.Run([&a] { return RunCompare(a); });
  c.Footer("Examples: candi compare scan2025.las scan2026.las -o change.las --method m3c2 --registration-error 0.003\n"
           "          candi compare wall_mesh.ply photogrammetry.ply -o deviation.ply --method c2m --tolerance 0.005");
}

}  // namespace

void AddInspectCommands(Command& root) {
  AddInfo(root);
  AddConvert(root);
  AddCompare(root);
}

}  // namespace candi::apps
