// candi register, candi register-scans, candi clean (PCL: in candi-pcl and candi-relief; the
// command lines are in register.cc): ICP refinement of MOVING onto FIXED, printing RMS and overlap
// before and after and the 4x4 transform (world coordinates); many scans at once, printing per
// scan, pair and loop (pipeline/scan_registration.h writes the moved files and the reports);
// statistical outlier removal and voxel thinning (photogrammetry/registration/cleaning.h), printing the counts
// removed per step.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/progress.h"
#include "io/point_io.h"
#include "pipeline/scan_registration.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"

namespace candi::apps {

namespace {

using photogrammetry::RegistrationResult;

void PrintResult(const RegisterArgs& a, const RegistrationResult& r) {
  std::printf("moving %s: %llu points (%llu in the solve)\n", a.moving.c_str(),
              static_cast<unsigned long long>(r.moving_points),
              static_cast<unsigned long long>(r.moving_solve_points));
  std::printf("fixed  %s: %llu points (%llu in the solve%s)\n", a.fixed.c_str(),
              static_cast<unsigned long long>(r.fixed_points),
              static_cast<unsigned long long>(r.fixed_solve_points),
              r.normals_estimated ? ", normals estimated" : "");
  std::printf("method %s-to-%s, max distance %g m, voxel %g m, local origin %.3f %.3f %.3f\n",
              "point", photogrammetry::IcpMethodName(r.method).c_str(), a.options.icp.max_correspondence_distance, a.options.icp.voxel,
              r.origin.x(), r.origin.y(), r.origin.z());
  std::printf("status %s: %s\n", photogrammetry::RegistrationStatusName(r.status).c_str(),
              r.message.c_str());
  std::printf("RMS before %.6f m, after %.6f m\n", r.rms_before, r.rms_after);
  std::printf("overlap before %.2f %%, after %.2f %% (moving points within %g m of the fixed "
              "cloud)\n", 100 * r.overlap_before, 100 * r.overlap_after, a.options.icp.max_correspondence_distance);
  const Eigen::Matrix4d m = r.fixed_from_moving.ToMatrix();
  std::printf("fixed_from_moving (world coordinates):\n");
  for (int i = 0; i < 4; ++i) {
    std::printf("  %15.12f %15.12f %15.12f %20.6f\n", m(i, 0), m(i, 1), m(i, 2), m(i, 3));
  }
}

void PrintScans(const pipeline::RegisteredScans& registered) {
  const std::vector<pipeline::ScanInput>& inputs = registered.scans;
  const photogrammetry::MultiRegistrationResult& r = registered.result;
  std::printf("%-24s %10s %9s %11s %9s %12s\n", "scan", "points", "connected", "moved m", "turned", "residual mm");
  for (size_t i = 0; i < r.scans.size(); ++i) {
    const auto& s = r.scans[i];
    std::printf("%-24s %10zu %9s %11.4f %8.4f° %12.3f\n", std::filesystem::path(inputs[i].label).filename().string().c_str(),
                registered.points[i], s.fixed ? "fixed" : (s.connected ? "yes" : "NO"), s.translation_change,
                s.rotation_change_deg, s.residual_rms * 1000);
  }
  std::printf("\n%-10s %8s %12s %12s %12s  %s\n", "pair", "overlap", "RMS start mm", "RMS pair mm", "RMS final mm",
              "status");
  for (const auto& p : r.pairs) {
    std::printf("%-10s %7.1f%% %12.2f %12.3f %12.3f  %s\n",
                (std::to_string(p.moving) + "-" + std::to_string(p.fixed)).c_str(), 100 * p.overlap,
                p.rms_before * 1000, p.rms_after * 1000, p.rms_global * 1000, p.reason.c_str());
  }
  double worst_t = 0, worst_r = 0;
  for (const auto& l : r.loops) {
    worst_t = std::max(worst_t, l.translation);
    worst_r = std::max(worst_r, l.rotation_deg);
  }
  std::printf("\nloops: %zu (pairwise fits composed around each; the worst %.2f mm, %.4f°)\n", r.loops.size(),
              worst_t * 1000, worst_r);
  if (r.control.count > 0) {
    std::printf("control targets: %d, RMSE %.2f mm (xy %.2f, z %.2f)\n", r.control.count, r.control.d3 * 1000,
                r.control.xy * 1000, r.control.z * 1000);
  }
  if (r.check.count > 0) {
    std::printf("check targets: %d, RMSE %.2f mm (xy %.2f, z %.2f)\n", r.check.count, r.check.d3 * 1000,
                r.check.xy * 1000, r.check.z * 1000);
  }
  std::printf("%s\n", r.message.c_str());
}

}  // namespace

int RunRegister(const RegisterArgs& a) {
  ConsoleTasks tasks;
  pipeline::RegisterPairCallbacks callbacks;
  callbacks.progress = tasks.Callbacks();
  callbacks.registered = [&a](const RegistrationResult& r) { PrintResult(a, r); };
  const pipeline::RegisteredPair r = pipeline::RegisterPair(a.options, a.moving, a.fixed, a.output, callbacks);
  if (r.result.status == photogrammetry::RegistrationStatus::kNotConverged) {
    std::fprintf(stderr, "candi: warning: ICP did not converge; the last transform was applied "
                         "(raise --iterations)\n");
  }
  std::printf("wrote %s (%zu points), time %.2f s\n", a.output.c_str(), r.points, r.seconds);
  return kOk;
}

int RunRegisterScans(const RegisterScansArgs& a) {
  ConsoleTasks tasks;
  pipeline::RegisterScansCallbacks callbacks;
  callbacks.progress = tasks.Callbacks();
  callbacks.coarse = [](const pipeline::ScanInput& moving, const pipeline::ScanInput& anchor,
                        const std::string& message) {
    std::printf("coarse %s onto %s: %s\n", moving.label.c_str(), anchor.label.c_str(), message.c_str());
  };
  callbacks.registered = PrintScans;
  const pipeline::RegisteredScans r = pipeline::RegisterScanFiles(a.options, a.scans, a.output_dir, callbacks);
  std::printf("wrote %zu scans and registration.json to %s, time %.2f s\n", r.scans.size(), a.output_dir.c_str(),
              r.seconds);
  size_t unconnected = 0;
  for (const auto& s : r.result.scans) unconnected += s.connected ? 0 : 1;
  if (unconnected > 0) {
    std::fprintf(stderr, "candi: warning: %zu scan(s) overlap no registered scan: written at their start pose\n",
                 unconnected);
  }
  return kOk;
}

namespace {

void PrintRow(const char* what, uint64_t count, uint64_t input) {
  std::printf("%-28s %12llu  %6.2f %%\n", what, static_cast<unsigned long long>(count),
              input ? 100.0 * static_cast<double>(count) / static_cast<double>(input) : 0.0);
}

}  // namespace

int RunClean(const CleanArgs& args) {
  const photogrammetry::CleanOptions& options = args.clean;
  options.Check();  // std::invalid_argument, exit 1
  io::OutputPointFormat(args.output);
  CheckOutputFolder(args.output);
  const auto start = std::chrono::steady_clock::now();
  const PointCloud cloud = io::ReadPointCloud(args.input);
  photogrammetry::CleanResult result;
  {
    ConsoleProgressOptions po;
    po.unit = "steps";
    ConsoleProgress progress("clean", po);
    result = photogrammetry::CleanPointCloud(options, cloud, progress.Callback());
  }
  io::WritePointCloud(args.output, result.cloud);
  const photogrammetry::CleanSummary& s = result.summary;
  std::printf("input %s\n", args.input.c_str());
  PrintRow("points in", s.input, s.input);
  PrintRow("removed: not finite", s.non_finite, s.input);
  if (options.sor) {
    char label[64];
    std::snprintf(label, sizeof(label), "removed: outliers (k %d, %gs)", options.sor_neighbours,
                  options.sor_std_multiplier);
    PrintRow(label, s.outliers, s.input);
  }
  if (options.voxel > 0) {
    char label[64];
    std::snprintf(label, sizeof(label), "removed: voxel %g m", options.voxel);
    PrintRow(label, s.thinned, s.input);
  }
  PrintRow("points out", s.output, s.input);
  std::printf("wrote %s, time %.2f s\n", args.output.c_str(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return kOk;
}

}  // namespace candi::apps
