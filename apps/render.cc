// candi render, section, opacity: see-through images of point files or an archive
// (pipeline/render.h; an archive's ensembles split over the ranks under mpirun,
// pipeline/render_ranks.h), sections (pipeline/section.h), and SPBR opacity by point-number
// adjustment from file to file (sampling/opacity.h; writes the kept points with the field
// spbr_multiplicity and records the parameters as a comment "candi_opacity alpha=...
// repeat_level=... pixel_size=... seed=...").
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/failure.h"
#include "apps/option_groups.h"
#include "core/atomic_file.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "pipeline/render.h"
#include "pipeline/render_ranks.h"
#include "pipeline/section.h"
#include "render/archive.h"
#include "render/build_record.h"
#include "render/mpi/mpi_session.h"
#include "render/view_json.h"
#include "sampling/opacity.h"

namespace candi::apps {

namespace {

struct RenderArgs {
  std::vector<std::string> inputs;
  pipeline::RenderOutputs outputs;     // png (8-bit), png16, save_view
  pipeline::RenderOptions options;
  std::string size = "1024x768";       // WxH (overrides a view's size when given explicitly)
  std::string view;                    // a view file (world coordinates)
  std::string background = "0,0,0";    // r,g,b
  std::string brightness = "auto";     // auto | none | a gain
  std::string mode = "auto";           // auto | memory | stream
  double memory_mb = 2048;             // stream mode and archives: z-buffers resident per pass
  double chunk_budget_mb = 256;        // archive input: chunks mapped at once (8 bytes a point)
  OrientationArgs orientation;
  ClipArgs clip;
  FieldArgs field;
  pipeline::GivenImageSettings given;  // the rest comes from a build's record
};

Brightness ParseBrightness(const std::string& text) {
  try {
    return Brightness::Parse(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--brightness ") + e.what());
  }
}

pipeline::RenderOptions RenderOptionsOf(const RenderArgs& a) {
  pipeline::RenderOptions o = a.options;
  o.clip = ParseClip(a.clip);
  ParseSize(a.size, "--size", &o.image.width, &o.image.height);
  o.image.background = ParseColour(a.background, "--background");
  o.image.brightness = ParseBrightness(a.brightness);
  o.colour_by = ParseFieldColouring(a.field);
  if (!o.alpha.empty() && o.alpha.size() != 1 && o.alpha.size() != a.inputs.size()) {
    throw std::invalid_argument("--alpha: give one value, or one per input (" + std::to_string(a.inputs.size()) + ")");
  }
  if (a.mode != "auto" && a.mode != "memory" && a.mode != "stream") {
    throw std::invalid_argument("--mode '" + a.mode + "': expected auto, memory or stream");
  }
  o.mode = a.mode == "memory" ? pipeline::RenderMode::kMemory
           : a.mode == "stream" ? pipeline::RenderMode::kStream : pipeline::RenderMode::kAuto;
  if (!(a.memory_mb > 0)) throw std::invalid_argument("--memory-budget must be > 0 MB");
  o.memory_budget = static_cast<uint64_t>(a.memory_mb * 1048576.0);
  o.Check();
  if (!a.view.empty()) {
    // A page's saved or shared view also carries the layers' shares and the clipping.
    render::SavedViewSettings saved;
    o.view = render::LoadView(a.view, &saved);
    for (size_t i = 0; i < saved.layer_names.size(); ++i) {
      o.layer_shares.push_back({saved.layer_names[i], saved.layer_shares[i]});
    }
    o.clip = o.clip.And(saved.clip);
  } else {
    o.orientation = ParseOrientation(a.orientation).Resolve();
  }
  return o;
}

void PrintRender(const std::string& output, const pipeline::RenderedImage& image, double gain) {
  const render::SpbrResult& r = image.result;
  std::printf("%s: %dx%d, SPBR L=%d (%d ensembles), %llu point copies, %.0f ms, gain %.2f, seed %llu\n",
              output.c_str(), image.world_camera.width, image.world_camera.height, r.repeat_level, r.ensembles,
              static_cast<unsigned long long>(r.copies), r.milliseconds, gain, static_cast<unsigned long long>(r.seed));
}

// Renders an archive, under mpirun as one of the ranks (pipeline/render_ranks.h); rank 0 alone
// writes the image (atomically). A failed rank makes every rank fail: no image.
int RenderArchive(const RenderArgs& a, pipeline::RenderOptions o) {
  if (!o.alpha.empty()) throw std::invalid_argument("--alpha needs point files: an archive holds one copy per point");
  if (!(a.chunk_budget_mb > 0)) throw std::invalid_argument("--chunk-budget must be > 0 MB");
  o.chunk_budget = static_cast<uint64_t>(a.chunk_budget_mb * 1048576.0);
  const pipeline::RanksRender r = pipeline::RenderArchiveOnRanks(o, a.inputs[0], RankReporting("no image written"));
  if (!r.failures.empty()) throw ReportedFailure(r.failures.front().exit_code);
  if (!r.root) return kOk;
  pipeline::RenderOutputs outputs = a.outputs;
  outputs.inputs = a.inputs;
  PrintRender(outputs.png, r.image, pipeline::WriteRender(o, r.image, outputs));
  return kOk;
}

int RunRender(const RenderArgs& a) {
  pipeline::RenderOptions o = RenderOptionsOf(a);
  for (const std::string& in : a.inputs) {
    // An archive, a build directory or a demo's output: what a page (candi view, a site) shows;
    // a build draws with its own settings where no flag says otherwise.
    const std::string archive = render::FindArchive(in);
    if (archive.empty()) continue;
    if (a.inputs.size() > 1) throw std::invalid_argument(in + " is an archive: render it alone");
    const std::string build = render::FindBuild(in);
    if (!build.empty() && pipeline::TakeBuildRenderSettings(render::ReadBuildRecord(build), a.given, &o)) {
      const ImageSettings& s = o.image;
      LogInfo("the build's render settings: L=" + std::to_string(s.spbr.repeat_level) + ", seed " +
              std::to_string(s.spbr.seed) + ", " + std::to_string(s.width) + "x" + std::to_string(s.height) +
              ", background " + std::to_string(s.background.r) + "," + std::to_string(s.background.g) + "," +
              std::to_string(s.background.b) + ", brightness " + s.brightness.ToString());
      o.Check();
    }
    RenderArgs one = a;
    one.inputs = {archive};
    return RenderArchive(one, o);
  }
  if (render::mpi::LaunchedByMpi()) {
    throw std::invalid_argument("under mpirun, candi render splits an archive (candi pack) over the ranks; "
                                "point files render in one process");
  }
  const pipeline::RenderedImage image = pipeline::RenderPointFiles(o, a.inputs);
  pipeline::RenderOutputs outputs = a.outputs;
  outputs.inputs = a.inputs;
  PrintRender(outputs.png, image, pipeline::WriteRender(o, image, outputs));
  return kOk;
}

}  // namespace

void AddRender(Command& root) {
  RenderArgs& a = root.Keep<RenderArgs>();
  pipeline::RenderOptions& o = a.options;
  Command c = root.Add("render", "Render point files see-through with SPBR (stochastic point-based rendering), "
                                 "merged into one image");
  c.Option("inputs", a.inputs, "Point files " CANDI_POINT_FILES_READ ", or one archive (candi pack, a build directory "
           "or a demo's output); under mpirun the ranks share the ensembles").Required();
  c.Option("-o,--output", a.outputs.png, "Output PNG (8-bit)").Required();
  c.Option("--png16", a.outputs.png16, "Also write a 16-bit PNG (for analysis)");
  pipeline::GivenImageSettings& given = a.given;
  c.Option("-L,--repeat-level", o.image.spbr.repeat_level, "Ensembles averaged (more: less noise, slower)")
      .OnGiven([&given] { given.repeat_level = true; });
  c.Option("--seed", o.image.spbr.seed, "Seed of the ensemble assignment").OnGiven([&given] { given.seed = true; });
  c.Option("--size", a.size, "Image size WxH").OnGiven([&o, &given] { o.size_given = given.size = true; });
  c.Option("--view", a.view, "View JSON (world coordinates) to render from; a page's saved view also sets the "
           "layers' shares and the clipping");
  c.Option("--save-view", a.outputs.save_view, "Write the view used as JSON (to repeat the render)");
  c.Option("--background", a.background, "Background colour r,g,b").OnGiven([&given] { given.background = true; });
  c.Option("--brightness", a.brightness, "auto, none, or a gain (transparent images get dark)")
      .OnGiven([&given] { given.brightness = true; });
  c.Option("--alpha", o.alpha, "Target opacity per input (one value for all, or one each)").Delimiter(',');
  c.Flag("--opaque", o.image.spbr.opaque, "Opaque rendering (L = 1, one point per pixel)");
  c.Option("--threads", o.threads, "Threads (0: all)").Range(0, 256);
  c.Option("--point-size", o.image.spbr.point_size, "Point size in pixels (>= 1; stochastic rounding)");
  c.Option("--preview", o.preview, "Render only the first k ensembles (progressive preview)");
  c.Option("--mode", a.mode, "auto, memory (fast, 10 B/point) or stream (bounded memory)");
  c.Option("--memory-budget", a.memory_mb, "Stream mode and archives: MB of z-buffers resident per pass (12 B per "
           "pixel and ensemble)");
  c.Option("--chunk-budget", a.chunk_budget_mb, "Archive input: MB of chunks mapped at once (8 B a point)");
  c.Option("--columns", o.columns, "XYZ/PTS column spec");
  AddOrientation(c, a.orientation,
                 {"Without --view: world up, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)",
                  "Without --view: the direction the view looks in, x,y,z (default: oblique, from above)",
                  "Without --view: a COLMAP model (e.g. WORK/sparse/0) whose frame the points are in: up and the "
                  "viewing side from its cameras"});
  AddClip(c, a.clip);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunRender(a); });
  c.Footer("Example: candi render building.ply foundation.ply -o site.png -L 100 --alpha 0.3,0.8");
}

namespace {

struct SectionArgs {
  std::vector<std::string> inputs;    // an archive, a build directory, or point files
  std::string output;                 // a directory: section.png .dxf .csv .svg .json
  std::string plane;                  // px,py,pz,nx,ny,nz
  std::string through;                // x1,y1[,z1],x2,y2[,z2]: the vertical plane through two points
  std::string path;                   // x1,y1,x2,y2,...: an unrolled section along a plan polyline
  double thickness = 0;               // m, > 0
  pipeline::SectionOptions options;
  std::string colours = "layer";      // layer | data
  std::string background = "255,255,255";
  ClipArgs clip;
};

section::SectionPath ParseSection(const SectionArgs& a) {
  const int given = !a.plane.empty() + !a.through.empty() + !a.path.empty();
  if (given != 1) throw std::invalid_argument("give one of --plane, --through and --path");
  if (!a.plane.empty()) {
    const std::vector<double> v = ParseNumbers(a.plane, ',', "--plane");
    if (v.size() != 6) throw std::invalid_argument("--plane '" + a.plane + "': expected px,py,pz,nx,ny,nz");
    return section::SectionPath::Plane({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  if (!a.through.empty()) {
    const std::vector<double> v = ParseNumbers(a.through, ',', "--through");
    if (v.size() == 4) return section::SectionPath::Through({v[0], v[1], 0}, {v[2], v[3], 0}, a.thickness);
    if (v.size() != 6) {
      throw std::invalid_argument("--through '" + a.through + "': expected x1,y1,x2,y2 or x1,y1,z1,x2,y2,z2");
    }
    return section::SectionPath::Through({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  const std::vector<double> v = ParseNumbers(a.path, ',', "--path");
  if (v.size() % 2 != 0) {
    throw std::invalid_argument("--path '" + a.path + "': expected x1,y1,x2,y2,... (plan vertices)");
  }
  std::vector<Eigen::Vector2d> plan;
  for (size_t i = 0; i + 1 < v.size(); i += 2) plan.push_back({v[i], v[i + 1]});
  size_t merged = 0;
  section::SectionPath s = section::SectionPath::Path(plan, a.thickness, &merged);
  if (merged > 0) LogWarning("--path: " + std::to_string(merged) + " repeated vertices merged");
  return s;
}

int RunSection(const SectionArgs& a) {
  const section::SectionPath path = ParseSection(a);
  const ClipRegion clip = ParseClip(a.clip);
  pipeline::SectionOptions o = a.options;
  if (a.colours != "layer" && a.colours != "data") {
    throw std::invalid_argument("--colours '" + a.colours + "': expected layer or data");
  }
  o.colours = a.colours == "data" ? pipeline::SectionColours::kData : pipeline::SectionColours::kLayer;
  o.background = ParseColour(a.background, "--background");
  const pipeline::SectionCut cut = pipeline::CutSection(o, a.inputs, path, clip);
  pipeline::WriteSection(cut, path, a.output);
  std::printf("%s: %s\n", a.output.c_str(), cut.describe.c_str());
  if (cut.archive) {
    std::printf("  read %llu of %llu chunks (%llu points)\n", static_cast<unsigned long long>(cut.chunks_read),
                static_cast<unsigned long long>(cut.chunks), static_cast<unsigned long long>(cut.points_read));
  }
  std::printf("  %-16s %10s %6s %10s\n", "layer", "points", "lines", "length m");
  for (const section::SectionLayerResult& l : cut.layers) {
    std::printf("  %-16s %10llu %6zu %10.3f%s\n", l.name.c_str(), static_cast<unsigned long long>(l.points),
                l.lines.size(), l.length, l.area ? "  (lies in the plane: no lines)" : "");
  }
  return kOk;
}

}  // namespace

void AddSection(Command& root) {
  SectionArgs& a = root.Keep<SectionArgs>();
  pipeline::SectionOptions& o = a.options;
  Command c = root.Add("section", "Cut a slab out of an archive or point files: a see-through image of it and its "
                                  "section lines per layer (DXF, CSV, SVG), in survey coordinates");
  c.Option("inputs", a.inputs, "An archive (candi pack), a build directory (candi build), or point files (a file's "
           "layer field names its layers)").Required();
  c.Option("-o,--output", a.output, "Output directory: section.png, .dxf, .csv, .svg and .json").Required();
  c.Option("--plane", a.plane, "A plane through a point with a normal: px,py,pz,nx,ny,nz (world coordinates)");
  c.Option("--through", a.through, "The vertical plane through two survey points, chainage from the first: "
           "x1,y1,x2,y2 (or with z)");
  c.Option("--path", a.path, "A plan polyline x1,y1,x2,y2,...: its vertical faces unrolled into one section");
  c.Option("--thickness", a.thickness, "Slab thickness in metres (> 0)").Required();
  c.Option("--spacing", o.spacing, "Section lines: vertex spacing in metres (0: from the points' density)");
  c.Option("--max-gap", o.max_gap, "Section lines: a gap in the data longer than this breaks a line (0: automatic)");
  c.Option("--width", o.width, "Image width in pixels");
  c.Option("--pixel", o.pixel, "Image: metres per pixel (overrides --width)");
  c.Option("-L,--repeat-level", o.spbr.repeat_level, "Image: SPBR ensembles");
  c.Option("--seed", o.spbr.seed, "Image: seed of the ensembles");
  c.Option("--point-size", o.spbr.point_size, "Image: point size in pixels");
  c.Option("--opacity", o.opacity, "Image: opacity of a pixel one point covers, (0, 1]; overlapping layers blend as "
           "SPBR blends");
  c.Option("--colours", a.colours, "Image colours: layer (one per layer) or data (the points' own)");
  c.Option("--background", a.background, "Image background r,g,b");
  c.Option("--layers", o.layers, "Only these layers (names)").Delimiter(',');
  c.Option("--columns", o.columns, "XYZ/PTS column spec");
  c.Option("--threads", o.threads, "Threads (0: all)").Range(0, 256);
  AddClip(c, a.clip);
  c.Run([&a] { return RunSection(a); });
  c.Footer("Example: candi section borobudur_out/ --through 0,-60,0,60 --thickness 0.2 -o section_ns/");
}

namespace {

std::string Comment(const sampling::OpacityOptions& o, const sampling::OpacitySummary& s) {
  return "candi_opacity alpha=" + FormatDouble(o.alpha) +
         " repeat_level=" + std::to_string(o.spbr.repeat_level) +
         " pixel_size=" + FormatDouble(s.pixel_size) +
         (o.image_size > 0 ? " image_size=" + std::to_string(o.image_size) : std::string()) +
         " seed=" + std::to_string(o.spbr.seed) + " method=" + sampling::DensityMethodName(o.density.method) +
         " radius=" + FormatDouble(s.radius);
}

std::string Percent(size_t part, size_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %%", whole ? 100.0 * part / whole : 0.0);
  return buf;
}

void PrintSummary(const sampling::OpacityOptions& o, const sampling::OpacitySummary& s) {
  std::printf("points in        %zu\n", s.points_in);
  std::printf("points out       %zu\n", s.points_out);
  std::printf("copies drawn     %llu (sum of spbr_multiplicity)\n",
              static_cast<unsigned long long>(s.total_copies));
  std::printf("removed          %zu (%s)\n", s.removed, Percent(s.removed, s.points_in).c_str());
  std::printf("replicated       %zu (%s)\n", s.replicated,
              Percent(s.replicated, s.points_in).c_str());
  std::printf("capped at L=%-5d %zu (%s)\n", o.spbr.repeat_level, s.capped,
              Percent(s.capped, s.points_in).c_str());
  std::printf("ratio n'/n       min %.4g  median %.4g  max %.4g\n", s.ratio_min, s.ratio_median,
              s.ratio_max);
  std::printf("pixel size       %.6g m  (s/S = %.4g, S = %.6g m^2, radius %.6g m)\n", s.pixel_size,
              s.point_area_ratio, s.area, s.radius);
  std::printf("median density   %.6g points/m^2\n", s.median_density);
  std::printf("target alpha     %.4g\n", o.alpha);
  std::printf("predicted alpha  %.4g (at the median density)\n", s.predicted_alpha);
  if (!s.message.empty()) std::printf("note             %s\n", s.message.c_str());
}

struct OpacityArgs {
  std::string input, output;
  sampling::OpacityOptions options;  // alpha and repeat_level are required
};

int RunOpacity(const OpacityArgs& args) {
  sampling::OpacityOptions options = args.options;
  options.density.seed = options.spbr.seed;
  options.Check();  // bad values: std::invalid_argument, exit 1
  io::OutputPointFormat(args.output);  // a known extension, and a writable folder, before the work
  CheckOutputFolder(args.output);
  const PointCloud cloud = io::ReadPointCloud(args.input);
  ConsoleProgress progress("opacity: density of " + args.input);
  options.density.progress = progress.Callback();
  sampling::OpacityResult result = sampling::AdjustOpacity(options, cloud);
  progress.Finish();
  result.cloud.meta.comments.push_back(Comment(options, result.summary));
  io::WritePointCloud(args.output, result.cloud);
  PrintSummary(options, result.summary);
  return kOk;
}

}  // namespace

void AddOpacity(Command& root) {
  OpacityArgs& a = root.Keep<OpacityArgs>();
  sampling::OpacityOptions& o = a.options;
  o.image_size = 0;  // no default on the command line: exactly one of --image-size and --pixel-size
  Command c = root.Add("opacity", "Set SPBR opacity by point-number adjustment: removes or replicates points (field "
                                  "spbr_multiplicity) for a target alpha");
  c.Option("input", a.input, "Input point file").Required();
  c.Option("output", a.output, "Output point file; format from its extension").Required();
  c.Option("--alpha", o.alpha, "Target opacity, 0..1").Required();
  c.Option("--repeat-level", o.spbr.repeat_level, "L, the number of ensembles the renderer averages").Required();
  c.Option("--image-size", o.image_size, "Pixels across the cloud's largest extent");
  c.Option("--pixel-size", o.pixel_size, "Or: the pixel footprint's side, metres");
  c.Option("--seed", o.spbr.seed, "Random seed");
  Arg k = c.Option("--neighbours", o.density.target_neighbours, "Neighbours of the median point for the automatic "
                   "density radius (default 32)");
  c.Option("--radius", o.density.radius, "Density radius, metres (default: automatic)").Excludes(k);
  c.Choice("--method", o.density.method,
           {{"kdtree", sampling::DensityMethod::kKdTree}, {"voxel", sampling::DensityMethod::kVoxel}},
           "Density estimate: kdtree or voxel");
  c.Option("--threads", o.density.threads, "Worker threads (0 = all)");
  c.Run([&a] { return RunOpacity(a); });
  c.Footer("Example: candi opacity site.ply site_a05.ply --alpha 0.5 --repeat-level 100 --image-size 1024");
}

}  // namespace candi::apps
