// candi sfm, dense, georef, colorcorrect, campaign: the building from photos
// (pipeline/photogrammetry.h): COLMAP structure from motion (a campaign's chunk mappers shared
// out over MPI ranks under mpirun, pipeline/sfm_ranks.h), CPU dense stereo (photos and fusion cells
// shared out over MPI ranks, pipeline/dense_ranks.h), georeferencing on
// surveyed targets; colour-card correction (pipeline/color_correct.h); and a synthetic photo
// campaign with its ground truth (reconstruction/photogrammetry/scenes/campaign.h).
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <utility>

#include "apps/commands.h"
#include "apps/failure.h"
#include "core/timer.h"
#include "io/point_io.h"
#include "pipeline/color_correct.h"
#include "pipeline/photogrammetry.h"
#include "pipeline/dense_ranks.h"
#include "pipeline/sfm_ranks.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"

namespace candi::apps {

namespace {

namespace pg = candi::photogrammetry;

struct SfmArgs {
  std::string images, workspace;
  pg::SfmOptions options;
  std::string matching = "auto";
  std::string colmap;  // "" = $CANDI_COLMAP, else options.colmap
};

int RunSfm(const SfmArgs& a) {
  pg::SfmOptions o = a.options;
  o.pairs.strategy = pg::ParsePairStrategy(a.matching);
  if (!a.colmap.empty()) {
    o.colmap = a.colmap;
  } else if (const char* env = std::getenv("CANDI_COLMAP"); env != nullptr && *env != '\0') {
    o.colmap = env;
  }
  o.Check();
  const pipeline::RanksSfm r =
      pipeline::StructureFromMotionOnRanks(o, a.images, a.workspace, RankReporting("no model written"));
  if (!r.failures.empty()) throw ReportedFailure(r.failures.front().exit_code);
  if (!r.root) return kOk;
  const pg::SfmSummary& s = r.summary;
  double total = 0;
  for (const auto& [stage, seconds] : s.stage_seconds) total += seconds;
  std::printf("COLMAP %s (%s), pairs by %s\n", s.colmap.version.c_str(), s.colmap.cuda ? "CUDA" : "CPU",
              s.matcher.c_str());
  std::printf("%-28s %zu / %zu\n", "pairs verified / matched", s.pairs_verified, s.pairs_tried);
  std::printf("%-28s %s\n", "images registered / total",
              (std::to_string(s.registered.size()) + " / " + std::to_string(s.images.size())).c_str());
  std::printf("%-28s %zu\n", "sparse points", s.points);
  std::printf("%-28s %.3f px\n", "mean reprojection error", s.mean_reprojection_error);
  std::printf("%-28s %.2f\n", "mean track length", s.mean_track_length);
  std::printf("%-28s %.1f s\n", "time", total);
  if (!s.chunked.chunks.empty()) {
    std::printf("chunks (survey frame minus the shift %s):\n", s.chunked.frame.ToString().c_str());
    std::printf("  %-10s %7s %10s %8s %8s %12s %10s  %s\n", "chunk", "photos", "registered", "points", "control",
                "control RMSE", "check RMSE", "");
    for (const pg::ChunkResult& k : s.chunked.chunks) {
      std::printf("  %-10s %7zu %10zu %8zu %8d %9.1f mm %7.1f mm  %s\n", k.name.c_str(), k.images, k.registered,
                  k.points, k.control_used, 1e3 * k.control.d3, 1e3 * k.check.d3,
                  k.tied ? "tied" : k.reason.c_str());
    }
    for (const pg::ChunkPairConsistency& p : s.chunked.pairs) {
      std::printf("  %s and %s overlap in %zu sparse points: median %.1f mm, 90%% %.1f mm apart as tied\n",
                  p.a.c_str(), p.b.c_str(), p.overlap, 1e3 * p.median, 1e3 * p.p90);
    }
    const pg::JointAdjustmentResult& j = s.chunked.joint;
    if (j.ran) {
      std::printf("  adjusted as one: %zu links joined %zu points across chunks, %zu observations added in other "
                  "chunks' photos (%zu refused); reprojection RMS %.3f -> %.3f px; control RMSE %.1f mm, check "
                  "%.1f mm (%d checks); %d iterations, %.1f s\n",
                  j.links, j.joined_points, j.extended, j.links_rejected, j.rms_before_px, j.rms_after_px,
                  1e3 * j.control.d3, 1e3 * j.check.d3, j.check.count, j.iterations, j.seconds);
    } else if (!j.reason.empty()) {
      std::printf("  not adjusted as one: %s\n", j.reason.c_str());
    }
  }
  std::printf("model: %s\ndense workspace: %s\n", s.model_dir.c_str(), s.dense_dir.c_str());
  return kOk;
}

}  // namespace

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
  c.Option("--matching", a.matching, "Pairs matched: auto (exhaustive up to --exhaustive-max-images, else "
           "sequential + retrieval, + positions with --priors), exhaustive, sequential, retrieval, positional");
  c.Option("--exhaustive-max-images", o.pairs.exhaustive_max_images, "Auto: every pair up to this many images")
      .Range(2, 1000000);
  c.Option("--sequential-overlap", o.pairs.sequential_overlap, "Sequential: each photo with the next N (name order)")
      .Range(0, 100000);
  c.Option("--retrieval-neighbours", o.pairs.retrieval_neighbours, "Retrieval: each photo with its N most similar "
           "(a vocabulary tree trained on the photos' own features)").Range(0, 100000);
  c.Option("--position-neighbours", o.pairs.position_neighbours, "Positions: each photo with its N nearest by the "
           "priors").Range(0, 100000);
  c.Option("--transitive-rounds", o.pairs.transitive_rounds, "After verification (not after exhaustive matching): "
           "rounds matching the photos that share verified neighbours, never tried; 0: none").Range(0, 100);
  c.Option("--transitive-neighbours", o.pairs.transitive_neighbours, "Transitive: a photo's new pairs a round at most, "
           "most shared neighbours first").Range(1, 100000);
  c.Option("--priors", o.priors, "Camera position priors, CSV name,E,N,H[,sigma] (candi campaign's priors.csv)");
  c.Option("--targets", o.chunks.targets, "Map each session folder apart and tie the chunks on these surveyed "
           "targets (georef's CSV); needs --picks");
  c.Option("--picks", o.chunks.picks, "The targets' picks in the photos, CSV name,image,u,v");
  c.FlagOff("--no-joint-adjustment", o.chunks.joint.enabled,
         "Chunks: keep each chunk as its targets tied it (default: then adjust all chunks as one, their points "
         "joined where matches link them, the control targets held to the survey)");
  c.Option("--chunk-parallel", o.chunks.parallel, "Chunk mappers run at once (under mpirun: on each rank, the "
           "chunks shared out over the ranks)").Range(1, 256);
  c.Option("--camera-model", o.camera_model, "COLMAP camera model (SIMPLE_RADIAL, OPENCV, ...)");
  c.FlagOff("--camera-per-image", o.single_camera, "Separate intrinsics per photo (default: one shared camera)");
  c.Option("--threads", o.threads, "Threads for feature extraction and matching (-1: all); COLMAP verifies and "
           "maps on one thread, so the model is the same on every run");
  c.Flag("--overwrite", o.overwrite, "Replace a previous run in the workspace");
  c.Flag("--resume", o.resume, "Continue a stopped run in the workspace: its finished stages and chunks are kept "
         "(same photos and options)");
  c.Run([&a] { return RunSfm(a); });
  c.Footer("Example: candi sfm photos/ -o work --max-image-size 1600");
}

namespace {

struct DenseArgs {
  std::string workspace, output;
  pipeline::DenseOptions options;
  double max_memory_mb = 0;
};

int RunDense(const DenseArgs& a) {
  pipeline::DenseOptions o = a.options;
  o.stereo.window_step = o.stereo.window_radius >= 3 ? 2 : 1;
  if (!(a.max_memory_mb >= 0)) throw std::invalid_argument("--max-memory must be >= 0 MB (0: a quarter of the machine's)");
  o.max_memory = static_cast<uint64_t>(a.max_memory_mb * 1048576.0);
  o.Check();
  io::OutputPointFormat(a.output);  // an unknown extension fails before the work
  const Stopwatch watch;
  // The points go to the file cell by cell, as rank 0 reads them back: never all held.
  std::unique_ptr<io::PointWriter> writer;
  const auto cells_out = [&](const PointCloud& cell) {
    if (!writer) {
      io::PointWriteSpec spec;
      spec.schema = cell.schema;
      spec.meta.comments.push_back(pipeline::DenseComment(a.workspace));
      writer = io::OpenPointWriter(a.output, spec);
    }
    writer->Write(cell);
  };
  const pipeline::RanksDense r =
      pipeline::DenseStereoOnRanks(o, a.workspace, RankReporting("no points written"), cells_out);
  if (!r.failures.empty()) throw ReportedFailure(r.failures.front().exit_code);
  if (!r.root) return kOk;
  const pipeline::DenseCloud& dense = r.dense;
  if (writer) writer->Close();  // rank 0 hands over at least one cell; a guard all the same
  std::printf("workspace %s: %zu images, %zu sparse points, sources from %s\n", a.workspace.c_str(), dense.images,
              dense.sparse_points, dense.sources_from_tracks ? "the tracks" : "the camera geometry (no tracks)");
  const double total_s = watch.Seconds();
  std::printf("stereo: %zu depth maps made, %zu found finished, %.2f s; image cache peak %.1f MB of %.0f MB\n",
              dense.maps_made, dense.maps_found, dense.stereo_seconds, dense.peak_cache_bytes / 1048576.0,
              dense.max_memory / 2 / 1048576.0);
  std::printf("filter: %llu of %llu pixels valid (%.1f %%), %zu photos without depth, %.2f s\n",
              static_cast<unsigned long long>(dense.valid_pixels), static_cast<unsigned long long>(dense.total_pixels),
              dense.total_pixels ? 100.0 * dense.valid_pixels / dense.total_pixels : 0.0, dense.empty_maps.size(),
              dense.filter_seconds);
  std::printf("fusion: %zu cells (%zu found finished), %.2f s\n", dense.tiles, dense.tiles_found, dense.fusion_seconds);
  std::printf("fused points: %zu -> %s\n", dense.points, a.output.c_str());
  std::printf("time: %.2f s, %.0f points/s, peak memory %.0f MB\n", total_s, total_s > 0 ? dense.points / total_s : 0.0,
              PeakMemoryMb());
  return kOk;
}

}  // namespace

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
  c.Option("--max-memory", a.max_memory_mb, "MB of images and maps held at once (0: a quarter of the machine's)");
  c.FlagOff("--no-maps", a.options.write_maps, "Remove stereo/'s depth and normal maps once the run has finished "
                                                "(they are the resume point until then)");
  c.Option("--seed", s.seed, "Random seed");
  c.Option("--threads", s.threads, "Threads (0: all)").Range(0, 256);
  c.Run([&a] { return RunDense(a); });
  c.Footer("Run again after an interruption, the same command keeps the depth maps and fusion cells already made.\n"
           "Example: candi dense workspace -o dense.ply --resolution-scale 0.5 --iterations 3");
}

namespace {

struct GeorefArgs {
  pipeline::GeorefFiles files;  // IN, --targets, -o, --model, --picks
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

int RunGeoref(const GeorefArgs& a) {
  pipeline::GeoreferenceFiles(a.options, a.files, PrintGeoref);
  return kOk;  // a fit that did not converge is reported (table, JSON, warning), not an error
}

}  // namespace

void AddGeoref(Command& root) {
  GeorefArgs& a = root.Keep<GeorefArgs>();
  pg::SimilarityFitOptions& fit = a.options.fit;
  Command c = root.Add("georef", "Georeference with total-station targets: robust similarity (Ceres), residuals per "
                                 "target, RMSE of control and check targets; per chunk, ties chunks into one frame");
  c.Option("input", a.files.input, "Point file, or a COLMAP sparse model folder").Required();
  c.Option("--targets", a.files.targets, "Targets CSV: name,E,N,H,role,accuracy[,x,y,z]").Required();
  c.Option("-o,--output", a.files.output, "Output point file (or folder, for a model); also writes OUT.georef.json")
      .Required();
  c.Option("--model", a.files.model, "COLMAP sparse model whose images the picks are in");
  c.Option("--picks", a.files.picks, "Picks CSV: name,image,u,v (pixels, undistorted images)");
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

namespace {

struct ColorCorrectArgs {
  std::string input, output;    // PNG image or point file with colours
  pipeline::ColorCard card;     // --patches, or --card and --corners
  pg::ColorCorrectionOptions options;
};

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

int RunColorCorrect(const ColorCorrectArgs& a) {
  pipeline::ColorCorrectFile(a.options, a.card, a.input, a.output, PrintColorCorrection);
  return kOk;
}

}  // namespace

void AddColorCorrect(Command& root) {
  ColorCorrectArgs& a = root.Keep<ColorCorrectArgs>();
  Command c = root.Add("colorcorrect", "Colour-card correction: a 3x4 matrix in linear RGB from the card's patches, "
                                       "applied to a PNG or point colours; CIEDE2000 before and after");
  c.Option("input", a.input, "PNG image or point file with colours").Required();
  c.Option("-o,--output", a.output, "Corrected output (same kind); also OUT.colorcorrect.json").Required();
  Arg patches = c.Option("--patches", a.card.patches, "CSV: patch,measured_r,measured_g,measured_b,reference_r,"
                         "reference_g,reference_b (0..255)");
  Arg card = c.Option("--card", a.card.card, "Photo of the colour card (8-bit PNG)");
  Arg corners = c.Option("--corners", a.card.corners, "CSV: patch,x0,y0,...,x3,y3,reference_r,reference_g,reference_b "
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

namespace {

struct CampaignArgs {
  std::string output;
  pg::CampaignOptions options;
  bool overwrite = false;
};

int RunCampaign(const CampaignArgs& a) {
  a.options.Check();
  ConsoleProgressOptions po;
  po.unit = "photos";
  ConsoleProgress progress("campaign", po);
  Stopwatch timer;
  const pg::Campaign c = pg::WriteCampaign(a.options, a.output, a.overwrite, progress.Callback());
  progress.Finish();
  std::printf("%s: %zu photos of %d x %d in %zu session(s), %zu terrace(s) (the lowest %.2f m across), "
              "%zu carved panels, %zu targets, %.1f s\n",
              a.output.c_str(), c.photos.size(), a.options.width, a.options.width * 3 / 4, c.chunks.size(),
              c.terrace_half_sides.size(), 2 * c.terrace_half_sides.front(), c.scene.carvings.size(),
              c.targets.size(), timer.Seconds());
  return kOk;
}

}  // namespace

void AddCampaign(Command& root) {
  CampaignArgs& a = root.Keep<CampaignArgs>();
  pg::CampaignOptions& o = a.options;
  Command c = root.Add("campaign", "A synthetic photo campaign with its ground truth: a terraced temple stand-in with "
                                   "carved panels, walked in sessions 2 m from its walls, painted survey targets, "
                                   "true cameras and surface");
  c.Option("output", a.output, "Folder to write (created)").Required();
  c.Option("--photos", o.photos, "Photos in all (the building is sized to them)").Range(8, 5000);
  c.Option("--size", o.width, "Long side of the photos, pixels (landscape 4:3)").Range(64, 8192);
  c.Option("--chunks", o.chunks, "Sessions the walks are split into (sectors of the building)").Range(1, 64);
  c.Option("--uav", o.uav_photos, "Of the photos, this many on a ring above (a session of its own)").Range(0, 5000);
  c.Option("--heights", o.heights, "Camera rows along each wall").Range(1, 4);
  c.Option("--distance", o.wall_distance, "Metres from the wall").Range(0.5, 10.0);
  c.Option("--overlap", o.overlap, "Overlap of neighbouring photos in a row").Range(0.2, 0.9);
  c.Option("--gps-sigma", o.gps_sigma, "Write GPS-like position priors with this noise, metres (0: none)");
  c.Option("--noise", o.noise_sigma, "Sensor noise, grey levels (0-255)");
  c.Option("--supersample", o.supersample, "Rays per pixel side").Range(1, 8);
  c.Option("--seed", o.seed, "Seed of the texture, carvings, noise and survey errors");
  c.Flag("--overwrite", a.overwrite, "Replace a campaign already in the folder");
  c.Run([&a] { return RunCampaign(a); });
  c.Footer("Example: candi campaign site --photos 60 --size 320 --chunks 3   (see docs/guide/campaign.md)");
}

}  // namespace candi::apps
