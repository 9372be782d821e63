// candi info, candi convert, candi pack, candi export: a point file's count, bounds, fields, format,
// shift and CRS; a point file in another format, shift or CRS (io/convert.h); point files packed
// into a render archive (render/archive_pack.h); a finished build's layers as COPC
// (pipeline/copc_export.h).
#include <algorithm>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/option_groups.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/convert.h"
#include "io/copc/copc_read.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "pipeline/copc_export.h"
#include "render/archive_pack.h"

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

}  // namespace

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

namespace {

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

namespace {

struct PackArgs {
  std::vector<std::string> inputs;
  std::string output;        // archive directory
  render::PackOptions options;
  double memory_mb = 400;    // sort buffers (~100 bytes a point)
  std::string columns;       // XYZ/PTS inputs
  FieldArgs field;           // the points coloured by a scalar field
};

int RunPack(const PackArgs& a) {
  if (!(a.memory_mb > 0)) throw std::invalid_argument("--memory must be > 0 MB");
  render::PackOptions o = a.options;
  o.memory_points = std::max<uint64_t>(o.chunk_points, static_cast<uint64_t>(a.memory_mb * 1048576.0 / 100));
  ConsoleProgress progress("pack");
  const FieldColouring colour_by = ParseFieldColouring(a.field);
  const render::PackSummary s =
      render::PackFiles(o, a.inputs, a.columns, a.output, progress.Callback(), colour_by);
  progress.Finish();
  std::printf("%s: %llu points in %llu chunks, %llu data file(s), %.2f bytes/point, %.1f s (%.1f M points/s: "
              "bounds %.1f s, sort and write %.1f s; input hashes %.1f s on another thread meanwhile)%s, %zu-byte records; "
              "largest quantization error %.3g, %.3g, %.3g mm\n",
              a.output.c_str(), static_cast<unsigned long long>(s.points), static_cast<unsigned long long>(s.chunks),
              static_cast<unsigned long long>(s.files), s.points ? static_cast<double>(s.bytes) / s.points : 0.0,
              s.seconds, s.points / s.seconds / 1e6, s.bounds_seconds, s.sort_seconds, s.hash_seconds,
              s.spilled_points ? ", sorted on disk" : "", s.record_bytes, 1e3 * s.max_error[0], 1e3 * s.max_error[1],
              1e3 * s.max_error[2]);
  if (s.colour_by) {
    const FieldLegend& l = *s.colour_by;
    std::printf("  coloured by %s (%s, %s to %s): %llu of %llu points outside the range, %llu without a value (grey)\n",
                l.field.c_str(), FieldScaleName(l.scale), FormatDouble(l.lo).c_str(), FormatDouble(l.hi).c_str(),
                static_cast<unsigned long long>(l.outside), static_cast<unsigned long long>(l.count),
                static_cast<unsigned long long>(l.undefined));
  }
  return kOk;
}

}  // namespace

void AddPack(Command& root) {
  PackArgs& a = root.Keep<PackArgs>();
  Command c = root.Add("pack", "Pack point files into a render archive: Morton-ordered chunks, 8 bytes a point, "
                               "memory-mapped by `candi render ARCHIVE`");
  c.Option("inputs", a.inputs, "Point files " CANDI_POINT_FILES_READ).Required();
  c.Option("-o,--output", a.output, "Archive directory (replaced if it is an archive)").Required();
  c.Option("--chunk-points", a.options.chunk_points, "Points per chunk at most").Range(64, 1 << 24);
  c.Option("--memory", a.memory_mb, "MB for sorting (larger inputs are bucketed on disk)");
  c.Option("--columns", a.columns, "XYZ/PTS column spec");
  c.Option("--threads", a.options.threads, "Threads (0: all)").Range(0, 256);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunPack(a); });
  c.Footer("Example: candi pack site.las photos.ply -o site.archive && candi render site.archive -o site.png   "
           "(candi pack deviations.ply --colour-by distance -o dev.archive: render, view and publish show its "
           "legend)");
}

namespace {

struct ExportCopcArgs {
  pipeline::CopcExportOptions options;
  double copc_memory_mb = 0;
};

int RunExportCopc(const ExportCopcArgs& a) {
  pipeline::CopcExportOptions o = a.options;
  o.copc.memory_bytes = CopcMemoryBytes(a.copc_memory_mb);
  std::optional<ConsoleProgress> progress;  // from the first point: no bar before an error
  StagedProgress closing("copc");            // each file's octree and chunks, once all is read
  const std::vector<pipeline::CopcFile> files = pipeline::ExportCopc(
      o,
      [&](uint64_t done, uint64_t total) {
        if (!progress) progress.emplace("copc");
        progress->Update(done, total);
        if (total > 0 && done >= total) progress->Finish();  // all read: the files close next
      },
      closing.Callback());
  closing.Finish();
  if (progress) progress->Finish();
  for (const pipeline::CopcFile& f : files) {
    std::printf("%s: %llu points (%s), %llu bytes\n", f.path.c_str(), static_cast<unsigned long long>(f.points),
                f.layer.empty() ? "every layer, point source ID = layer index" : ("layer " + f.layer).c_str(),
                static_cast<unsigned long long>(f.bytes));
  }
  return kOk;
}

}  // namespace

void AddExport(Command& root) {
  Command e = root.Add("export", "Write a finished build's layers in another format, without rebuilding");
  e.RequireSubcommand();
  ExportCopcArgs& a = root.Keep<ExportCopcArgs>();
  pipeline::CopcExportOptions& o = a.options;
  Command c = e.Add("copc", "COPC (cloud-optimized LAZ) of a finished build, for Potree, QGIS and CloudCompare: "
                            "every layer in one file, the layer as point source ID, and with --layers each layer "
                            "beside its PLY (what a scene's \"copc\" makes candi build write)");
  c.Option("build", o.build, "A finished build's folder (archive.json, layers/)").Required();
  c.Option("-o,--out", o.out, "The whole scene's file (default: BUILD/copc/<scene>.copc.laz)");
  c.Flag("--layers", o.copc.layers, "Also each layer as BUILD/layers/<name>.copc.laz");
  AddCopcMemory(c, a.copc_memory_mb);
  c.Run([&a] { return RunExportCopc(a); });
  c.Footer("Example: candi export copc borobudur_archive --layers   (then open "
           "borobudur_archive/copc/borobudur.copc.laz in QGIS, or with Potree)");
}

}  // namespace candi::apps
