// candi sfm, dense, georef, register, register-scans, clean, colorcorrect, foundation (and relief, relief.cc): the
// building from photos (pipeline/photogrammetry.h), colour-card correction, the foundation from
// CAD sections (pipeline/foundation.h). register and clean run in candi-pcl (pcl_commands.cc).
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/timer.h"
#include "io/image/png_io.h"
#include "io/layer_clouds.h"
#include "io/mesh_io.h"
#include "io/point_io.h"
#include "pipeline/foundation.h"
#include "pipeline/photogrammetry.h"
#include "reconstruction/photogrammetry/color_correct.h"
#include "sampling/layer_colours.h"

namespace candi::apps {

namespace {

namespace fs = std::filesystem;
namespace pg = candi::photogrammetry;

// ---------------------------------------------------------------------------------------- sfm

struct SfmArgs {
  std::string images, workspace;
  pg::SfmOptions options;
  std::string colmap;  // "" = $CANDI_COLMAP, else options.colmap
};

int RunSfm(const SfmArgs& a) {
  pg::SfmOptions o = a.options;
  if (!a.colmap.empty()) {
    o.colmap = a.colmap;
  } else if (const char* env = std::getenv("CANDI_COLMAP"); env != nullptr && *env != '\0') {
    o.colmap = env;
  }
  o.Check();
  const pg::SfmSummary s = pipeline::StructureFromMotion(o, a.images, a.workspace);
  double total = 0;
  for (const auto& [stage, seconds] : s.stage_seconds) total += seconds;
  std::printf("COLMAP %s (%s), %s\n", s.colmap.version.c_str(), s.colmap.cuda ? "CUDA" : "CPU", s.matcher.c_str());
  std::printf("%-28s %s\n", "images registered / total",
              (std::to_string(s.registered.size()) + " / " + std::to_string(s.images.size())).c_str());
  std::printf("%-28s %zu\n", "sparse points", s.points);
  std::printf("%-28s %.3f px\n", "mean reprojection error", s.mean_reprojection_error);
  std::printf("%-28s %.2f\n", "mean track length", s.mean_track_length);
  std::printf("%-28s %.1f s\n", "time", total);
  std::printf("model: %s\ndense workspace: %s\n", s.model_dir.c_str(), s.dense_dir.c_str());
  return kOk;
}

void AddSfm(Command& root) {
  SfmArgs& a = root.Keep<SfmArgs>();
  pg::SfmOptions& o = a.options;
  Command c = root.Add("sfm", "Structure from motion with COLMAP: photos to a sparse model and a dense workspace "
                              "(WORKSPACE/dense)");
  c.Option("images", a.images, "Folder of photos (other files are ignored)").Required();
  c.Option("-o,--output", a.workspace, "Workspace folder (created)").Required();
  c.Option("--colmap", a.colmap, "COLMAP executable (default: $CANDI_COLMAP, else colmap)");
  c.Option("--max-image-size", o.max_image_size, "Longest side in pixels for SIFT and the dense images")
      .Range(64, 100000);
  c.Option("--max-features", o.max_features, "SIFT features per image").Range(64, 1000000);
  c.Option("--exhaustive-max-images", o.exhaustive_max_images, "Exhaustive matching up to this many images, "
           "sequential matching above").Range(2, 1000000);
  c.Option("--camera-model", o.camera_model, "COLMAP camera model (SIMPLE_RADIAL, OPENCV, ...)");
  c.FlagOff("--camera-per-image", o.single_camera, "Separate intrinsics per photo (default: one shared camera)");
  c.Option("--threads", o.threads, "Threads for feature extraction and matching (-1: all); COLMAP verifies and "
           "maps on one thread, so the model is the same on every run");
  c.Flag("--overwrite", o.overwrite, "Replace a previous run in the workspace");
  c.Run([&a] { return RunSfm(a); });
  c.Footer("Example: candi sfm photos/ -o work --max-image-size 1600");
}

// -------------------------------------------------------------------------------------- dense

struct DenseArgs {
  std::string workspace, output;
  pipeline::DenseOptions options;
};

int RunDense(const DenseArgs& a) {
  pipeline::DenseOptions o = a.options;
  o.stereo.window_step = o.stereo.window_radius >= 3 ? 2 : 1;
  o.Check();
  io::OutputPointFormat(a.output);  // an unknown extension fails before the work
  const Stopwatch watch;
  pipeline::DenseCloud dense = pipeline::DenseStereo(o, a.workspace);
  std::printf("workspace %s: %zu images, %zu sparse points\n", a.workspace.c_str(), dense.images, dense.sparse_points);
  io::WritePointCloud(a.output, dense.cloud);
  const double total_s = watch.Seconds();
  std::printf("depth maps: %llu of %llu pixels valid (%.1f %%)\n", static_cast<unsigned long long>(dense.valid_pixels),
              static_cast<unsigned long long>(dense.total_pixels),
              dense.total_pixels ? 100.0 * dense.valid_pixels / dense.total_pixels : 0.0);
  std::printf("fused points: %zu -> %s\n", dense.cloud.size(), a.output.c_str());
  std::printf("time: %.2f s (reading and PatchMatch %.2f s), %.0f points/s\n", total_s, dense.stereo_seconds,
              total_s > 0 ? dense.cloud.size() / total_s : 0.0);
  return kOk;
}

void AddDense(Command& root) {
  DenseArgs& a = root.Keep<DenseArgs>();
  pg::PatchMatchOptions& s = a.options.stereo;
  Command c = root.Add("dense", "CPU multi-view PatchMatch stereo on a COLMAP dense workspace (images/ + sparse/): "
                                "depth and normal maps (written to stereo/ for COLMAP's stereo_fusion), fused into "
                                "coloured points with normals");
  c.Option("workspace", a.workspace, "COLMAP dense workspace (e.g. from candi sfm)").Required();
  c.Option("-o,--output", a.output, "Point file " CANDI_POINT_FILES_WRITTEN).Required();
  c.Option("--resolution-scale", s.resolution_scale, "Resample images by this factor (0, 1]");
  c.Option("--iterations", s.iterations, "PatchMatch rounds (propagation + refinement)");
  c.Option("--window", s.window_radius, "Matching window radius, pixels");
  c.Option("--views", s.num_source_views, "Source views per reference image");
  c.Option("--min-consistent", s.min_consistent_views, "Source views that must agree geometrically");
  c.Option("--min-views", a.options.fusion.min_views, "Fusion: views per point");
  c.FlagOff("--no-maps", a.options.write_maps, "Do not write stereo/{depth,normal}_maps");
  c.Option("--seed", s.seed, "Random seed");
  c.Option("--threads", s.threads, "Threads (0: all)").Range(0, 256);
  c.Run([&a] { return RunDense(a); });
  c.Footer("Example: candi dense workspace -o dense.ply --resolution-scale 0.5 --iterations 3");
}

// ------------------------------------------------------------------------------------- georef

struct GeorefArgs {
  std::string input;    // point file, or a COLMAP sparse model folder
  std::string targets;  // targets CSV (reconstruction/photogrammetry/georef.h)
  std::string output;   // point file (IN a point file) or folder (IN a model)
  std::string model;    // COLMAP sparse model of the picks (default: IN if a model)
  std::string picks;    // picks CSV name,image,u,v
  pipeline::GeorefOptions options;
};

std::string Fixed(double v, int digits = 4) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

void PrintGeoref(const pg::GeorefResult& r) {
  std::printf("%-12s %-7s %9s %9s %9s %9s %9s %9s %5s  %s\n", "target", "role", "dX m", "dY m", "dZ m", "dXY m",
              "d3D m", "reproj px", "views", "status");
  for (size_t i = 0; i < r.targets.size(); ++i) {
    const pg::SurveyTarget& t = r.targets[i];
    const Eigen::Vector3d& d = r.residuals[i];
    const bool used = t.unused_reason.empty();
    const std::string status = !used ? "unused: " + t.unused_reason : r.outlier[i] ? "OUTLIER" : "ok";
    std::printf("%-12s %-7s %9s %9s %9s %9s %9s %9s %5d  %s\n", t.name.c_str(), pg::TargetRoleName(t.role).c_str(),
                used ? Fixed(d.x()).c_str() : "-", used ? Fixed(d.y()).c_str() : "-", used ? Fixed(d.z()).c_str() : "-",
                used ? Fixed(d.head<2>().norm()).c_str() : "-", used ? Fixed(d.norm()).c_str() : "-",
                Fixed(t.reprojection_px, 2).c_str(), t.views, status.c_str());
  }
  std::printf("\n%-26s %5s %9s %9s %9s %9s %9s\n", "RMSE", "n", "X m", "Y m", "Z m", "XY m", "3D m");
  const std::pair<const char*, const pg::Rmse*> rows[] = {{"control (outliers out)", &r.control}, {"check", &r.check}};
  for (const auto& [name, e] : rows) {
    std::printf("%-26s %5d %9s %9s %9s %9s %9s\n", name, e->count, Fixed(e->x).c_str(), Fixed(e->y).c_str(),
                Fixed(e->z).c_str(), Fixed(e->xy).c_str(), Fixed(e->d3).c_str());
  }
  const Sim3& t = r.survey_from_model;
  std::printf("\nscale %.9f, rotation %.6f deg, shift %s, outlier threshold %.4f m, %s\n", t.scale,
              Eigen::AngleAxisd(t.rotation).angle() * 180 / M_PI, r.frame.ToString().c_str(), r.fit.threshold,
              r.fit.converged ? "converged" : "NOT CONVERGED");
  std::printf("layout: collinearity s2/s1 %.3g, planarity s3/s1 %.3g\n", r.fit.collinearity, r.fit.planarity);
  for (const std::string& w : r.fit.warnings) std::printf("warning: %s\n", w.c_str());
}

// IN, a point file, streamed through the transform into OUT.
void GeoreferencePointFile(const GeorefArgs& a, const pg::GeorefResult& r) {
  auto reader = io::OpenPointReader(a.input);
  io::PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  if (!a.options.crs.empty()) spec.meta.crs = a.options.crs;
  spec.frame = r.frame;
  spec.count = reader->info().count;
  auto writer = io::OpenPointWriter(a.output, spec);
  PointCloud chunk;
  while (reader->Read(1 << 20, &chunk) > 0) {
    pg::ApplySimilarity(r.survey_from_model, r.frame, &chunk);
    writer->Write(chunk);
  }
  writer->Close();
  LogInfo("wrote " + std::to_string(writer->points_written()) + " points to " + a.output);
}

// IN, a COLMAP model, moved into OUT (a model folder) with its points.
void GeoreferenceModel(const GeorefArgs& a, const pg::GeorefResult& r, PointCloud points) {
  fs::create_directories(a.output);
  const Sim3 local_from_model(r.survey_from_model.scale, r.survey_from_model.rotation,
                              r.survey_from_model.translation - r.frame.origin);
  pg::WriteGeoreferencedColmapModel(a.input, local_from_model, a.output);
  pg::ApplySimilarity(r.survey_from_model, r.frame, &points);
  io::WritePointCloud(a.output + "/points.ply", points);
}

int RunGeoref(const GeorefArgs& a) {
  a.options.Check();  // bad values: exit 1
  const bool input_is_model = fs::is_directory(a.input);
  if (!input_is_model) {
    io::DetectPointFormat(a.input);  // readable and known, before the work
    io::OutputPointFormat(a.output);
  }
  CheckOutputFolder(a.output);
  const std::string model_dir = input_is_model ? a.input : a.model;
  pg::ColmapGeorefInput model;
  if (!model_dir.empty()) model = pg::ReadColmapForGeoref(model_dir);
  const pg::GeorefResult result =
      pipeline::FitGeoref(a.options, a.targets, model_dir.empty() ? nullptr : &model, a.picks);
  PrintGeoref(result);
  for (const std::string& w : result.fit.warnings) LogWarning(w);
  if (input_is_model) {
    GeoreferenceModel(a, result, model.points);
  } else {
    GeoreferencePointFile(a, result);
  }
  WriteFileAtomic(a.output + ".georef.json", pipeline::GeorefReport(a.options, result).dump(2) + "\n");
  return kOk;  // a fit that did not converge is reported (table, JSON, warning), not an error
}

void AddGeoref(Command& root) {
  GeorefArgs& a = root.Keep<GeorefArgs>();
  pg::SimilarityFitOptions& fit = a.options.fit;
  Command c = root.Add("georef", "Georeference with total-station targets: robust similarity (Ceres), residuals per "
                                 "target, RMSE of control and check targets; per chunk, ties chunks into one frame");
  c.Option("input", a.input, "Point file, or a COLMAP sparse model folder").Required();
  c.Option("--targets", a.targets, "Targets CSV: name,E,N,H,role,accuracy[,x,y,z]").Required();
  c.Option("-o,--output", a.output, "Output point file (or folder, for a model); also writes OUT.georef.json")
      .Required();
  c.Option("--model", a.model, "COLMAP sparse model whose images the picks are in");
  c.Option("--picks", a.picks, "Picks CSV: name,image,u,v (pixels, undistorted images)");
  c.Choice("--loss", fit.loss,
           {{"none", pg::RobustLoss::kNone}, {"huber", pg::RobustLoss::kHuber}, {"cauchy", pg::RobustLoss::kCauchy}},
           "Robust loss: huber, cauchy or none");
  c.Option("--loss-scale", fit.loss_scale, "Robust loss scale, m").Positive();
  c.Option("--outlier-threshold", fit.outlier_threshold, "Flag residuals above this, m "
           "(default: 4 x max(robust sigma, target accuracy))").NonNegative();
  c.FlagOff("--rigid", fit.estimate_scale, "Rigid fit (scale 1)");
  c.Option("--crs", a.options.crs, "CRS of the survey frame (e.g. EPSG:32749), stated in OUT");
  c.Option("--targets-crs", a.options.targets_crs, "CRS the targets are given in (e.g. EPSG:4979 for GNSS); "
           "transformed into --crs with PROJ before the fit");
  c.Run([&a] { return RunGeoref(a); });
  c.Footer("Example: candi georef chunk1.ply --targets targets.csv -o chunk1_utm.ply");
}

// ------------------------------------------------------------------------- register and clean

void AddRegister(Command& root) {
  RegisterArgs& a = root.Keep<RegisterArgs>();
  pg::RegistrationOptions& o = a.icp;
  Command c = root.Add("register", "ICP refinement of MOVING onto FIXED (PCL, local coordinates): RMS, overlap, the "
                                   "4x4 transform; writes MOVING moved");
  c.Option("moving", a.moving, "Point file to move").Required();
  c.Option("fixed", a.fixed, "Point file to register onto").Required();
  c.Option("-o,--output", a.output, "MOVING after the transform (its precision and shift kept)").Required();
  c.Option("--max-distance", o.max_correspondence_distance, "Largest correspondence distance, m");
  c.Option("--iterations", o.max_iterations, "Largest number of ICP iterations");
  c.Choice("--method", o.method,
           {{"point", pg::IcpMethod::kPointToPoint}, {"plane", pg::IcpMethod::kPointToPlane}},
           "point (point-to-point) or plane (point-to-plane; normals estimated when FIXED has none)");
  c.Option("--voxel", o.voxel, "Thin both clouds to this voxel size for the solve, m");
  c.Option("--transform-out", a.transform_out, "Write the transform and figures as JSON");
  c.Option("--initial", a.initial, "Initial transform (JSON as --transform-out writes)");
  c.Run([&a] { return RunRegister(a); });
  c.Footer("Example: candi register scan2.las scan1.las -o scan2_reg.las --max-distance 0.2 --transform-out t.json");
}

void AddRegisterScans(Command& root) {
  RegisterScansArgs& a = root.Keep<RegisterScansArgs>();
  pg::MultiRegistrationOptions& o = a.options;
  Command c = root.Add("register-scans", "Many scans into one frame at once: overlapping pairs by point-to-plane ICP, "
                                         "then all poses in one robust Ceres solve (loops close), with control targets");
  c.Option("scans", a.scans, "Point files, one scan each (an E57 file with several scans counts as several, each "
           "starting from its stored pose)").Required();
  c.Option("-o,--output", a.output_dir, "Folder for the moved scans and registration.json").Required();
  c.Option("--poses", a.poses, "Start poses: JSON, a 4x4 world_from_scan per scan (or a registration.json); "
           "default identity");
  c.Flag("--coarse", a.coarse, "Scans without a start pose are first aligned onto scan 0 by FPFH features and "
         "RANSAC (PCL)");
  c.Option("--targets", a.targets, "Targets seen in the scans, CSV: name,scan,x,y,z,E,N,H[,role[,accuracy]] (scan: "
           "index or file name; role control or check)");
  c.Option("--fixed", a.fixed, "Scans held at their start pose, e.g. 0,2 (default: scan 0, or none with 3+ "
           "control targets)");
  c.Option("--max-distance", o.max_correspondence_distance, "Coarse ICP pairing distance, m");
  c.Option("--solve-distance", o.solve_distance, "Fine ICP and global solve pairing distance, m");
  c.Option("--iterations", o.icp_iterations, "ICP iterations per stage");
  c.Option("--voxel", o.voxel, "Thin every scan to this voxel first, m (0: off)");
  c.Option("--icp-voxel", o.icp_voxel, "Thin the moving scan of a pair further for ICP, m (0: off)");
  c.Option("--min-overlap", o.min_overlap, "Overlap a pair needs to count (share of points within the solve distance)");
  c.Option("--loss-scale", o.loss_scale, "Huber scale of the global solve's point-to-plane terms, m");
  c.Option("--rounds", o.outer_iterations, "Global solve rounds (correspondences re-found each)");
  c.Option("--correspondences", o.correspondences_per_pair, "Correspondences per pair and direction");
  c.Option("--coarse-voxel", a.coarse_options.voxel, "With --coarse: thin both scans to this for the features, m");
  c.Option("--coarse-radius", a.coarse_options.feature_radius, "With --coarse: the FPFH features' support radius, m "
           "(> the coarse voxel)");
  c.Option("--coarse-inlier-distance", a.coarse_options.inlier_distance, "With --coarse: a moved point within this "
           "of the other scan is an inlier, m");
  c.Option("--coarse-min-inliers", a.coarse_options.min_inlier_fraction, "With --coarse: the share of inliers a pose "
           "needs, [0, 1] (lower only for scans sharing less than half their points)");
  c.Option("--coarse-iterations", a.coarse_options.max_iterations, "With --coarse: RANSAC iterations");
  c.Option("--seed", a.coarse_options.seed, "With --coarse: the seed of RANSAC's sampling");
  c.Option("--format", a.format, "Extension of the moved scans (ply, las, laz, copc.laz, e57, xyz; default: each scan's own)");
  c.Run([&a] { return RunRegisterScans(a); });
  c.Footer("Example: candi register-scans st1.las st2.las st3.las st4.las -o registered --targets targets.csv\n"
           "         (then candi compare registered/st1.las registered/st2.las -o overlap.las --method m3c2)");
}

void AddClean(Command& root) {
  CleanArgs& a = root.Keep<CleanArgs>();
  pg::CleanOptions& o = a.clean;
  Command c = root.Add("clean", "Statistical outlier removal (PCL) and voxel thinning (one real point per voxel); "
                                "every field kept");
  c.Option("input", a.input, "Input point file").Required();
  c.Option("-o,--output", a.output, "Output point file").Required();
  c.Option("--sor-k", o.sor_neighbours, "Outlier removal: neighbours averaged");
  c.Option("--sor-std", o.sor_std_multiplier, "Outlier removal: threshold in standard deviations");
  c.FlagOff("--no-sor", o.sor, "Skip outlier removal");
  c.Option("--voxel", o.voxel, "Keep the point nearest each voxel's centre, voxel side m");
  c.Run([&a] { return RunClean(a); });
  c.Footer("Example: candi clean dense.ply -o dense_clean.ply --voxel 0.01");
}

// ------------------------------------------------------------------------------- colorcorrect

struct ColorCorrectArgs {
  std::string input, output;    // PNG image or point file with colours
  std::string patches;          // CSV of measured vs reference patch colours, or
  std::string card, corners;    // the card photo (PNG) and its patches' corners CSV
  pg::ColorCorrectionOptions options;
};

bool IsPng(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

std::vector<pg::ColorPatch> Patches(const ColorCorrectArgs& a) {
  if (!a.patches.empty()) return pg::ReadColorPatches(a.patches);
  const io::PngImage card = io::ReadPng(a.card);
  if (card.bit_depth != 8) throw InputError(a.card, "", "the card photo must be an 8-bit PNG");
  return pg::SamplePatches(card.image8, pg::ReadPatchQuads(a.corners), a.corners);
}

void PrintColorCorrection(const pg::ColorCorrection& c) {
  std::printf("%-16s %10s %10s  %s\n", "patch", "dE00 before", "dE00 after", "status");
  for (const pg::PatchDeltaE& p : c.patches) {
    std::printf("%-16s %10.2f %10.2f  %s\n", p.name.c_str(), p.before, p.after,
                p.outlier ? "OUTLIER (not fitted)" : "ok");
  }
  std::printf("%-16s %10.2f %10.2f\n%-16s %10.2f %10.2f\n", "mean (fitted)", c.mean_before, c.mean_after,
              "max (fitted)", c.max_before, c.max_after);
  std::printf("colour difference: CIEDE2000, CIELAB D65; matrix (linear RGB, out = M [in; 1]):\n");
  for (int r = 0; r < 3; ++r) {
    std::printf("  %9.5f %9.5f %9.5f %9.5f\n", c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2), c.matrix(r, 3));
  }
  for (const std::string& w : c.warnings) std::printf("warning: %s\n", w.c_str());
}

std::string ColorCorrectionJson(const pg::ColorCorrection& c) {
  nlohmann::json j;
  j["matrix_linear_rgb"] = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) {
    j["matrix_linear_rgb"].push_back({c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2), c.matrix(r, 3)});
  }
  j["delta_e"] = "CIEDE2000";
  for (const pg::PatchDeltaE& p : c.patches) {
    j["patches"].push_back({{"name", p.name}, {"before", p.before}, {"after", p.after}, {"outlier", p.outlier}});
  }
  j["mean_before"] = c.mean_before;
  j["mean_after"] = c.mean_after;
  j["max_before"] = c.max_before;
  j["max_after"] = c.max_after;
  j["warnings"] = c.warnings;
  return j.dump(2) + "\n";
}

void CorrectPointFile(const ColorCorrectArgs& a, const pg::ColorMatrix& m) {
  PointCloud cloud = io::ReadPointCloud(a.input);
  if (!cloud.schema.colors) throw InputError(a.input, "", "the points have no colours");
  pg::ApplyColorMatrix(m, &cloud);
  io::WritePointCloud(a.output, cloud);
}

void CorrectImage(const ColorCorrectArgs& a, const pg::ColorMatrix& m) {
  io::PngImage png = io::ReadPng(a.input);
  Image8& image8 = png.image8;
  const int channels = png.bit_depth == 8 ? image8.channels() : png.image16.channels();
  if (channels < 3) throw InputError(a.input, "", "a grey image cannot be colour-corrected");
  if (png.bit_depth == 8) {
    pg::ApplyColorMatrix(m, &image8);
    io::WritePng(a.output, image8, png.text);
  } else {
    pg::ApplyColorMatrix(m, &png.image16);
    io::WritePng(a.output, png.image16, png.text);
  }
}

int RunColorCorrect(const ColorCorrectArgs& a) {
  a.options.Check();
  if (a.patches.empty() == (a.card.empty() || a.corners.empty())) {
    throw std::invalid_argument("give either --patches or both --card and --corners");
  }
  const bool png = IsPng(a.input);
  if (png != IsPng(a.output)) throw std::invalid_argument("IN and OUT must both be PNG images or both point files");
  if (!png) {
    io::DetectPointFormat(a.input);
    io::OutputPointFormat(a.output);
  } else if (!fs::is_regular_file(a.input)) {
    throw InputError(a.input, "", "cannot read the image (no such file)");
  }
  const pg::ColorCorrection c = pg::FitColorCorrection(a.options, Patches(a));
  PrintColorCorrection(c);
  for (const std::string& w : c.warnings) LogWarning(w);
  if (png) {
    CorrectImage(a, c.matrix);
  } else {
    CorrectPointFile(a, c.matrix);
  }
  WriteFileAtomic(a.output + ".colorcorrect.json", ColorCorrectionJson(c));
  return kOk;
}

void AddColorCorrect(Command& root) {
  ColorCorrectArgs& a = root.Keep<ColorCorrectArgs>();
  Command c = root.Add("colorcorrect", "Colour-card correction: a 3x4 matrix in linear RGB from the card's patches, "
                                       "applied to a PNG or point colours; CIEDE2000 before and after");
  c.Option("input", a.input, "PNG image or point file with colours").Required();
  c.Option("-o,--output", a.output, "Corrected output (same kind); also OUT.colorcorrect.json").Required();
  Arg patches = c.Option("--patches", a.patches, "CSV: patch,measured_r,measured_g,measured_b,reference_r,"
                         "reference_g,reference_b (0..255)");
  Arg card = c.Option("--card", a.card, "Photo of the colour card (8-bit PNG)");
  Arg corners = c.Option("--corners", a.corners, "CSV: patch,x0,y0,...,x3,y3,reference_r,reference_g,reference_b "
                         "(corners in pixels, around the patch)");
  patches.Excludes(card).Excludes(corners);
  card.Needs(corners);
  corners.Needs(card);
  c.Option("--outlier-delta-e", a.options.outlier_delta_e, "A patch predicted worse than this (CIEDE2000) may be "
           "left out").Positive();
  c.Option("--max-outliers", a.options.max_outliers, "Patches that may be left out").Range(0, 100);
  c.Run([&a] { return RunColorCorrect(a); });
  c.Footer("Example: candi colorcorrect photo.png -o photo_corrected.png --patches card.csv");
}

// --------------------------------------------------------------------------------- foundation

struct FoundationArgs {
  std::string input;   // the section drawing (ASCII DXF)
  std::string output;  // point file; merged unless split
  pipeline::FoundationPointsOptions options;
  std::string mesh;    // optional mesh output (.obj .off .ply); per layer if several
  bool split = false;  // one point file per layer, <stem>_<layer><ext>
  std::string axis_x;  // drawing x of the axis, m; "" = through the reference point
};

// "<stem>_<layer><ext>" beside `path`.
std::string LayerPath(const std::string& path, const std::string& layer) {
  const fs::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + layer + p.extension().string())).string();
}

void PrintFoundation(const pipeline::FoundationPoints& f, const mesh::RevolveOptions& revolve) {
  std::printf("%-8s %-8s %10s %-9s %-6s %10s %12s %10s  %s\n", "layer", "colour", "points", "symmetric", "mode",
              "asymmetry", "area m^2", "triangles", "mesh check");
  size_t total = 0;
  for (size_t k = 0; k < f.surfaces.size(); ++k) {
    const mesh::LayerSurface& s = f.surfaces[k];
    total += f.clouds[k].size();
    std::printf("%-8s %-8s %10zu %-9s %-6s %10.2e %12.1f %10zu  %s\n", s.layer.c_str(),
                sampling::DefaultLayerColour(s.layer, k).name.c_str(), f.clouds[k].size(),
                s.mode == mesh::RevolveMode::kSweep ? "yes" : "no", mesh::RevolveModeName(s.mode).c_str(), s.asymmetry,
                f.areas[k], s.mesh.faces.size(), s.checked ? s.check.Summary().c_str() : "not checked");
  }
  std::printf("%-8s %-8s %10zu\n", "total", "", total);
  if (revolve.mode == mesh::RevolveMode::kAuto) {
    std::printf("mode auto: layers whose sides mirror within %.3g of their extent are swept, the others blended\n",
                revolve.symmetry_tolerance);
  }
}

int RunFoundation(const FoundationArgs& a) {
  pipeline::FoundationPointsOptions o = a.options;
  if (!a.axis_x.empty()) o.surface.revolve.axis_x = ParseNumbers(a.axis_x, ',', "--axis-x").at(0);
  if (o.sample.per_triangle > 0) {
    o.sample.mode = sampling::SurfaceSamplingMode::kPerTriangle;
  } else if (o.sample.count == 0 && o.sample.density == 0) {
    o.sample.density = pipeline::kDefaultFoundationDensity;  // a negative one fails Check
  }
  o.Check();  // bad values: std::invalid_argument, exit 1
  io::OutputPointFormat(a.output);  // a known extension, before the work
  const Stopwatch watch;
  const pipeline::FoundationPoints f = pipeline::DigitizeFoundation(o, a.input);
  for (size_t k = 0; k < f.surfaces.size(); ++k) {
    if (!a.mesh.empty()) {
      io::WriteMesh(f.surfaces.size() == 1 ? a.mesh : LayerPath(a.mesh, f.surfaces[k].layer), f.surfaces[k].mesh);
    }
    if (a.split) io::WritePointCloud(LayerPath(a.output, f.surfaces[k].layer), f.clouds[k]);
  }
  if (!a.split) io::WriteLayerClouds(a.output, f.clouds, f.Names());  // one file with a layer field
  std::printf("drawing %s: %s, %zu layer(s) with sections, units %s\n", a.input.c_str(),
              a.split ? "points per layer" : "merged points", f.drawing_layers, f.unit_name.c_str());
  PrintFoundation(f, o.surface.revolve);
  const double total = watch.Seconds();
  std::printf("time: %.2f s (meshes and checks %.2f s, sampling %.2f s, writing %.2f s)\n", total, f.mesh_seconds,
              f.sample_seconds, total - f.mesh_seconds - f.sample_seconds);
  return kOk;
}

void AddFoundation(Command& root) {
  FoundationArgs& a = root.Keep<FoundationArgs>();
  mesh::FoundationOptions& s = a.options.surface;
  sampling::SurfaceSampleOptions& sample = a.options.sample;
  Command c = root.Add("foundation", "Foundation layers from a CAD section drawing (DXF): profiles, Hermite "
                                     "resampling, rotational blending or sweep, mesh, uniform points");
  c.Option("drawing", a.input, "Section drawing (ASCII DXF)").Required();
  c.Option("-o,--output", a.output, "Point file " CANDI_POINT_FILES_WRITTEN ": merged with a layer field, or one per layer "
           "with --split").Required();
  c.Option("--layers", a.options.layers, "Layers to build, e.g. A,B,C,D (default: all with a section)").Delimiter(',');
  c.Option("--samples-per-side", s.profile.samples_per_side, "N: Hermite samples per side (>= 2)");
  c.Option("--angular-steps", s.revolve.angular_steps, "M: steps per half-turn (>= 2)");
  Arg count = c.Option("--count", sample.count, "Total points, split over the layers by area");
  Arg density = c.Option("--density", sample.density, "Points per m^2 (default 50)");
  Arg per = c.Option("--per-triangle", sample.per_triangle, "The paper's mode: this many points in every triangle "
                     "(not uniform; for comparison)");
  count.Excludes(density);
  per.Excludes(count).Excludes(density);
  c.Choice("--mode", s.revolve.mode,
           {{"auto", mesh::RevolveMode::kAuto}, {"blend", mesh::RevolveMode::kBlend},
            {"sweep", mesh::RevolveMode::kSweep}},
           "auto (sweep symmetric layers, blend the others), blend or sweep");
  c.Option("--mesh", a.mesh, "Also write the mesh (.obj .off .ply); <stem>_<layer><ext> when several layers");
  c.Flag("--split", a.split, "One point file per layer: <stem>_<layer><ext>");
  c.Flag("--close-base", s.mesh.close_base, "Close each mesh's bottom ring (a solid)");
  c.FlagOff("--no-check", s.check, "Skip the CGAL mesh checks");
  c.FlagOff("--no-self-intersection", s.check_options.self_intersections,
            "Skip only CGAL's self-intersection test (the slowest check)");
  c.Option("--axis-x", a.axis_x, "Drawing x of the vertical axis, m (default: through each layer's highest point)");
  c.Option("--symmetry-tolerance", s.revolve.symmetry_tolerance, "auto: sides mirrored within this fraction of the "
           "section's extent count as symmetric");
  c.Option("--chord-tolerance", s.dxf.chord_tolerance, "Bulge arcs: largest chord error, m");
  c.Option("--join-tolerance", s.section.join_tolerance, "LINE ends closer than this join, m");
  c.Option("--seed", sample.seed, "Random seed of the sampling");
  c.Option("--threads", sample.threads, "Threads (0: all)").Range(0, 256);
  c.Run([&a] { return RunFoundation(a); });
  c.Footer("Example: candi foundation examples/borobudur/foundation.dxf -o foundation.ply --layers A,B,C,D --mesh "
           "foundation.obj");
}

}  // namespace

void AddDigitizeCommands(Command& root) {
  AddSfm(root);
  AddDense(root);
  AddGeoref(root);
  AddRegister(root);
  AddRegisterScans(root);
  AddClean(root);
  AddColorCorrect(root);
  AddFoundation(root);
  AddReliefCommands(root);
}

}  // namespace candi::apps
