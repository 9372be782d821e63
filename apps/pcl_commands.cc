// candi register, candi clean (PCL, in candi-pcl only): ICP refinement of MOVING onto FIXED
// (reconstruction/photogrammetry/registration.h), printing RMS and overlap before and after and the
// 4x4 transform (world coordinates) and writing MOVING moved, in its own format, precision and
// shift (and optionally the transform and figures as JSON); statistical outlier removal and voxel
// thinning (cleaning.h), printing the counts removed per step, every attribute of the kept points,
// the shift and the position precision kept.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/transform.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/cleaning.h"
#include "reconstruction/photogrammetry/local_points.h"
#include "reconstruction/photogrammetry/registration.h"

namespace candi::apps {

namespace {

using photogrammetry::RegistrationOptions;
using photogrammetry::RegistrationResult;

// The 4x4 of a transform JSON: {"fixed_from_moving": [[...] x4]} (as --transform-out writes) or
// a bare [[...] x4]; must be rigid.
Rigid3 ReadTransform(const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFileToString(path));
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(path, "byte " + std::to_string(e.byte), "not JSON: " + std::string(e.what()));
  } catch (const nlohmann::json::exception& e) {  // e.g. a number beyond double's range
    throw InputError(path, "", "not JSON: " + std::string(e.what()));
  }
  const nlohmann::json& m = j.is_object() ? j.value("fixed_from_moving", nlohmann::json()) : j;
  Eigen::Matrix4d t;
  if (!m.is_array() || m.size() != 4) {
    throw InputError(path, "fixed_from_moving", "expected a 4x4 array of numbers");
  }
  for (int r = 0; r < 4; ++r) {
    if (!m[r].is_array() || m[r].size() != 4) {
      throw InputError(path, "fixed_from_moving row " + std::to_string(r), "expected 4 numbers");
    }
    for (int c = 0; c < 4; ++c) {
      if (!m[r][c].is_number()) {
        throw InputError(path, "fixed_from_moving row " + std::to_string(r), "expected 4 numbers");
      }
      t(r, c) = m[r][c].get<double>();
    }
  }
  try {
    const Sim3 s = Sim3FromMatrix(t, 1e-4);  // hand-written matrices: 4-5 digits
    if (std::abs(s.scale - 1.0) > 1e-4) throw std::invalid_argument("scale is not 1");
    return Rigid3(s.rotation, s.translation);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, "fixed_from_moving", "not a rigid transform: " + std::string(e.what()));
  }
}

PointCloud ReadInput(const std::string& path) {
  PointCloud cloud = io::ReadPointCloud(path);
  if (cloud.empty()) throw InputError(path, "", "no points");
  photogrammetry::CheckFinitePositions(cloud, path);
  return cloud;
}

void PrintResult(const RegisterArgs& a, const RegistrationResult& r) {
  std::printf("moving %s: %llu points (%llu in the solve)\n", a.moving.c_str(),
              static_cast<unsigned long long>(r.moving_points),
              static_cast<unsigned long long>(r.moving_solve_points));
  std::printf("fixed  %s: %llu points (%llu in the solve%s)\n", a.fixed.c_str(),
              static_cast<unsigned long long>(r.fixed_points),
              static_cast<unsigned long long>(r.fixed_solve_points),
              r.normals_estimated ? ", normals estimated" : "");
  std::printf("method %s-to-%s, max distance %g m, voxel %g m, local origin %.3f %.3f %.3f\n",
              "point", photogrammetry::IcpMethodName(r.method).c_str(), a.icp.max_correspondence_distance, a.icp.voxel,
              r.origin.x(), r.origin.y(), r.origin.z());
  std::printf("status %s: %s\n", photogrammetry::RegistrationStatusName(r.status).c_str(),
              r.message.c_str());
  std::printf("RMS before %.6f m, after %.6f m\n", r.rms_before, r.rms_after);
  std::printf("overlap before %.2f %%, after %.2f %% (moving points within %g m of the fixed "
              "cloud)\n", 100 * r.overlap_before, 100 * r.overlap_after, a.icp.max_correspondence_distance);
  const Eigen::Matrix4d m = r.fixed_from_moving.ToMatrix();
  std::printf("fixed_from_moving (world coordinates):\n");
  for (int i = 0; i < 4; ++i) {
    std::printf("  %15.12f %15.12f %15.12f %20.6f\n", m(i, 0), m(i, 1), m(i, 2), m(i, 3));
  }
}

void WriteTransformJson(const RegisterArgs& a, const RegistrationResult& r) {
  const Eigen::Matrix4d m = r.fixed_from_moving.ToMatrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); };
  const nlohmann::json j = {
      {"fixed_from_moving", rows},
      {"moving", a.moving},
      {"fixed", a.fixed},
      {"status", photogrammetry::RegistrationStatusName(r.status)},
      {"message", r.message},
      {"method", photogrammetry::IcpMethodName(r.method)},
      {"iterations", r.iterations},
      {"max_distance_m", a.icp.max_correspondence_distance},
      {"rms_before_m", number(r.rms_before)},
      {"rms_after_m", number(r.rms_after)},
      {"overlap_before", r.overlap_before},
      {"overlap_after", r.overlap_after}};
  WriteFileAtomic(a.transform_out, j.dump(2) + "\n");
}

}  // namespace

int RunRegister(const RegisterArgs& args) {
  RegistrationOptions options = args.icp;
  options.Check();  // bad values: std::invalid_argument, exit 1
  io::OutputPointFormat(args.output);                // a known extension, before the work
  CheckOutputFolder(args.output);
  if (!args.transform_out.empty()) CheckOutputFolder(args.transform_out);
  if (!args.initial.empty()) options.initial = ReadTransform(args.initial);
  const auto start = std::chrono::steady_clock::now();
  const PointCloud moving = ReadInput(args.moving);
  const PointCloud fixed = ReadInput(args.fixed);
  RegistrationResult result;
  {
    ConsoleProgressOptions po;
    po.unit = "iterations";
    ConsoleProgress progress("ICP", po);
    result = photogrammetry::RegisterPointClouds(options, moving, fixed, progress.Callback());
  }
  PrintResult(args, result);
  if (!args.transform_out.empty()) WriteTransformJson(args, result);
  if (result.status == photogrammetry::RegistrationStatus::kNoOverlap) {
    throw InputError(args.moving, "", "cannot be registered onto " + args.fixed + ": " +
                                          result.message);
  }
  io::WritePointCloud(args.output, photogrammetry::TransformPointCloud(result.fixed_from_moving, moving));
  if (result.status == photogrammetry::RegistrationStatus::kNotConverged) {
    std::fprintf(stderr, "candi: warning: ICP did not converge; the last transform was applied "
                         "(raise --iterations)\n");
  }
  std::printf("wrote %s (%zu points), time %.2f s\n", args.output.c_str(), moving.size(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
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
