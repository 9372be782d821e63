// candi bench dense --data DIR: candi's dense stereo on the real Sceaux photos against the OpenMVS
// reference cloud that ships beside them (DIR/README.md):
//   1. the photos are resampled to the sparse model's 1600 px camera (INTER_AREA, JPEG q95) and
//      COLMAP's image_undistorter makes the dense workspace (in a temporary folder, removed);
//   2. candi's PatchMatch + fusion run on it at --scale (0.5: OpenMVS's half resolution), timed;
//   3. both dense clouds are scored in the sparse model's frame, where OpenMVS's cloud also lies:
//      the distance from each sparse point (track >= 3 views, the best-triangulated) to the nearest
//      dense point, and the distances between the two dense clouds in both directions. Distances
//      are given as a fraction of the median camera-to-point depth, since the model has no scale.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/timer.h"
#include "io/image/jpeg_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/registration/point_index.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"

namespace candi::bench {

namespace pg = candi::photogrammetry;
namespace fs = std::filesystem;

namespace {

constexpr double kOpenMvsSeconds = 375.0;  // DIR/README.md: OpenMVS 2.3, this machine class
constexpr size_t kOpenMvsPoints = 402504;

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::nan("");
  const size_t k = static_cast<size_t>(q * (v.size() - 1));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

std::vector<Eigen::Vector3f> Positions(const PointCloud& cloud, const Eigen::Vector3d& origin) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) out.push_back((cloud.WorldPosition(i) - origin).cast<float>());
  return out;
}

// Distances (not squared) from each query to the nearest point of `index`.
std::vector<double> Distances(const pg::PointIndex& index, const std::vector<Eigen::Vector3f>& queries) {
  std::vector<double> d = index.NearestSquaredDistances(queries, Eigen::Matrix4d::Identity());
  for (double& x : d) x = std::sqrt(x);
  return d;
}

// The 1600 px images the sparse model was made from, and the undistorted workspace.
std::string PrepareWorkspace(const pg::ColmapModel& model, const std::string& photos,
                             const std::string& sparse, const std::string& temp) {
  const std::string images = temp + "/images";
  fs::create_directories(images);
  for (const auto& [id, image] : model.images) {
    const pg::ColmapCamera& camera = model.cameras.at(image.camera_id);
    const Image8 full = io::ReadImageRgb8(photos + "/" + image.name);
    io::WriteJpeg(images + "/" + image.name, pg::ResampleArea(full, camera.width, camera.height), 95);
  }
  const std::string dense = temp + "/dense";
  const std::vector<std::string> argv = {"colmap", "image_undistorter", "--image_path", images,
                                         "--input_path", sparse, "--output_path", dense,
                                         "--output_type", "COLMAP"};
  const std::string log = temp + "/image_undistorter.log";
  const int code = pg::RunLogged(argv, log);
  if (code != 0) {
    throw InputError("bench dense: colmap image_undistorter exited with " + std::to_string(code) +
                     "; last lines of " + log + ":\n" + pg::TailOfFile(log, 10));
  }
  return dense;
}

}  // namespace

int RunDenseSceaux(const BenchOptions& args) {
  const std::string photos = args.data + "/photos/sceaux_castle";
  const std::string sparse = args.data + "/colmap/sceaux_1600_sparse";
  const std::string reference = args.data + "/dense/sceaux_openmvs_dense.ply";
  for (const std::string& p : {photos, sparse, reference}) {
    if (!fs::exists(p)) throw InputError(p + ": not found (bench dense --data expects ../shared/data)");
  }
  const pg::ColmapModel model = pg::ReadColmapModel(sparse);
  const std::string temp = (fs::temp_directory_path() / ("candi_bench_sceaux_" + std::to_string(::getpid()))).string();
  const TempFolder cleanup(temp, RegisterTempPath(temp));  // removed at the end, by an exception or an interrupt

  Stopwatch watch;
  const std::string workspace = PrepareWorkspace(model, photos, sparse, temp);
  const double prep_s = watch.Seconds();

  pg::PatchMatchOptions o;
  o.resolution_scale = args.scale;
  o.iterations = args.iterations;
  o.threads = args.threads;
  o.Check();
  const pg::StereoInput input = pg::ReadDenseWorkspace(workspace);
  watch.Restart();
  const pg::PatchMatchResult stereo = pg::RunPatchMatch(o, input);
  const double stereo_s = watch.Seconds();
  const PointCloud ours = pg::FuseDepthMaps(pg::FusionOptions(), stereo.maps);
  const double dense_s = watch.Seconds();
  const PointCloud openmvs = io::ReadPointCloud(reference);

  // Scale of the scene: median depth of the sparse points in the cameras that see them.
  std::vector<double> depths;
  std::vector<Eigen::Vector3d> sparse_points;
  for (const auto& [id, point] : model.points3d) {
    for (const pg::ColmapTrackElement& e : point.track) {
      const pg::ColmapImage& image = model.images.at(e.image_id);
      depths.push_back((image.cam_from_world_rotation * point.xyz + image.cam_from_world_translation).z());
    }
    if (point.track.size() >= 3) sparse_points.push_back(point.xyz);
  }
  const double depth = Quantile(depths, 0.5);
  CANDI_CHECK(depth > 0) << "sparse model: no points in front of the cameras";
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : sparse_points) origin += p / static_cast<double>(sparse_points.size());
  std::vector<Eigen::Vector3f> sparse_local;
  for (const Eigen::Vector3d& p : sparse_points) sparse_local.push_back((p - origin).cast<float>());

  const std::vector<Eigen::Vector3f> ours_local = Positions(ours, origin), mvs_local = Positions(openmvs, origin);
  const pg::PointIndex ours_index(ours_local), mvs_index(mvs_local);
  const std::vector<double> sparse_to_ours = Distances(ours_index, sparse_local);
  const std::vector<double> sparse_to_mvs = Distances(mvs_index, sparse_local);
  const std::vector<double> ours_to_mvs = Distances(mvs_index, ours_local);
  const std::vector<double> mvs_to_ours = Distances(ours_index, mvs_local);
  auto within = [&](const std::vector<double>& d, double tol) {
    size_t n = 0;
    for (double x : d) n += x <= tol * depth;
    return d.empty() ? 0.0 : 100.0 * n / d.size();
  };

  std::printf("Sceaux (11 photos, COLMAP model at %dx%d, dense at scale %.2f, %d iterations, %d thread(s)); "
              "distances as %% of the median depth %.3f (model units)\n",
              model.cameras.begin()->second.width, model.cameras.begin()->second.height, args.scale,
              args.iterations, args.threads, depth);
  std::printf("  workspace (resample + colmap image_undistorter): %.1f s, not counted\n", prep_s);
  std::printf("%-28s %9s %9s %10s %14s %14s %12s\n", "cloud", "points", "seconds", "points/s",
              "sparse median", "sparse <=0.5%", "to other med");
  std::printf("%-28s %9zu %9.1f %10.0f %13.3f%% %13.1f%% %11.3f%%\n", "OpenMVS 2.3 (README figures)",
              openmvs.size(), kOpenMvsSeconds, kOpenMvsPoints / kOpenMvsSeconds,
              100 * Quantile(sparse_to_mvs, 0.5) / depth, within(sparse_to_mvs, 0.005),
              100 * Quantile(mvs_to_ours, 0.5) / depth);
  std::printf("%-28s %9zu %9.1f %10.0f %13.3f%% %13.1f%% %11.3f%%\n", "candi dense (this run)", ours.size(),
              dense_s, ours.size() / dense_s, 100 * Quantile(sparse_to_ours, 0.5) / depth,
              within(sparse_to_ours, 0.005), 100 * Quantile(ours_to_mvs, 0.5) / depth);
  std::printf("  candi: PatchMatch %.1f s + fusion %.1f s; depth maps %.1f %% valid; candi points within "
              "0.5 %% / 1 %% of OpenMVS's cloud: %.1f %% / %.1f %%; OpenMVS's within 1 %% of candi's: %.1f %%\n",
              stereo_s, dense_s - stereo_s,
              stereo.total_pixels ? 100.0 * stereo.valid_pixels / stereo.total_pixels : 0.0,
              within(ours_to_mvs, 0.005), within(ours_to_mvs, 0.01), within(mvs_to_ours, 0.01));
  return 0;
}

}  // namespace candi::bench
