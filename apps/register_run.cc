// candi register, candi register-scans, candi clean (PCL: in candi-pcl and candi-relief; their
// command lines are in register.cc): ICP refinement of MOVING onto FIXED
// (reconstruction/photogrammetry/registration.h), printing RMS and overlap before and after and
// the 4x4 transform (world coordinates) and writing MOVING moved, in its own format, precision and
// shift (and optionally the transform and figures as JSON); many scans at once
// (multi_registration.h), printing per scan, pair and loop and writing the moved scans and
// registration.json; statistical outlier removal and voxel thinning (cleaning.h), printing the
// counts removed per step, every attribute of the kept points, the shift and the position
// precision kept.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/transform.h"
#include "io/e57/e57_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/cleaning.h"
#include "reconstruction/photogrammetry/csv_table.h"
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

using photogrammetry::MultiRegistrationResult;

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json MatrixJson(const Rigid3& t) {
  const Eigen::Matrix4d m = t.ToMatrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  return rows;
}

// A 4x4 rigid transform from JSON (`where` names it in errors).
Rigid3 RigidFromJson(const nlohmann::json& m, const std::string& path, const std::string& where) {
  Eigen::Matrix4d t;
  if (!m.is_array() || m.size() != 4) throw InputError(path, where, "expected a 4x4 array of numbers");
  for (int r = 0; r < 4; ++r) {
    if (!m[r].is_array() || m[r].size() != 4) throw InputError(path, where, "expected a 4x4 array of numbers");
    for (int c = 0; c < 4; ++c) {
      if (!m[r][c].is_number()) throw InputError(path, where, "expected a 4x4 array of numbers");
      t(r, c) = m[r][c].get<double>();
    }
  }
  try {
    const Sim3 s = Sim3FromMatrix(t, 1e-4);
    if (std::abs(s.scale - 1.0) > 1e-4) throw std::invalid_argument("scale is not 1");
    return Rigid3(s.rotation, s.translation);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, where, "not a rigid transform: " + std::string(e.what()));
  }
}

// Start poses: a JSON array of 4x4 world_from_scan (one per scan), or a registration.json whose
// "scans" hold them. `given` says which scans had one (all, with this file).
std::vector<Rigid3> ReadStartPoses(const std::string& path, size_t count) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFileToString(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "", "not JSON: " + std::string(e.what()));
  }
  std::vector<nlohmann::json> matrices;
  if (j.is_object() && j.contains("scans") && j["scans"].is_array()) {
    for (const auto& s : j["scans"]) matrices.push_back(s.value("world_from_scan", nlohmann::json()));
  } else if (j.is_array()) {
    for (const auto& m : j) matrices.push_back(m);
  } else {
    throw InputError(path, "", "expected an array of 4x4 matrices, or a registration.json");
  }
  if (matrices.size() != count) {
    throw InputError(path, "", "holds " + std::to_string(matrices.size()) + " poses for " +
                                   std::to_string(count) + " scans");
  }
  std::vector<Rigid3> poses;
  for (size_t i = 0; i < count; ++i) poses.push_back(RigidFromJson(matrices[i], path, "pose " + std::to_string(i)));
  return poses;
}

// One scan to register: a point file, or one scan of an E57 file that holds several.
struct ScanInput {
  std::string path;
  int e57_scan = -1;   // >= 0: this scan of the E57 file, read in its own frame
  std::string label;   // how it is named: the file, or "file#k" for an E57's scan k
  std::string stem;    // the output's name without extension
  bool has_pose = false;
  Rigid3 pose;         // an E57 scan's stored pose: its start
};

// The files as scans: an E57 file with several scans counts as that many, each starting from
// its stored pose.
std::vector<ScanInput> ExpandScans(const std::vector<std::string>& files) {
  std::vector<ScanInput> out;
  for (const std::string& f : files) {
    const std::filesystem::path p(f);
    std::string ext = p.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const std::vector<io::E57ScanInfo> e57 = ext == ".e57" ? io::ListE57Scans(f) : std::vector<io::E57ScanInfo>();
    if (e57.size() <= 1) {
      out.push_back({f, -1, f, p.stem().string(), false, Rigid3()});
      continue;
    }
    for (size_t k = 0; k < e57.size(); ++k) {
      ScanInput in{f, static_cast<int>(k), f + "#" + std::to_string(k) + " (" + e57[k].name + ")",
                   p.stem().string() + "_" + std::to_string(k), true, Rigid3(e57[k].rotation, e57[k].translation)};
      out.push_back(in);
    }
  }
  return out;
}

PointCloud ReadScan(const ScanInput& in) {
  if (in.e57_scan < 0) return ReadInput(in.path);
  auto reader = io::OpenE57ScanReader(in.path, static_cast<size_t>(in.e57_scan));
  PointCloud cloud, chunk;
  while (reader->Read(1 << 20, &chunk) > 0) {
    if (cloud.empty()) {
      cloud = chunk;
    } else {
      cloud.Append(chunk);
    }
  }
  if (cloud.empty()) throw InputError(in.path, "scan " + std::to_string(in.e57_scan), "no points");
  photogrammetry::CheckFinitePositions(cloud, in.label);
  return cloud;
}

// Targets CSV: name,scan,x,y,z,E,N,H[,role[,accuracy]]; scan by index, by file name or stem, or
// (an E57's scan) by its label "file#k" or output stem "stem_k".
std::vector<photogrammetry::ScanTarget> ReadScanTargets(const std::string& path,
                                                        const std::vector<ScanInput>& scans) {
  const photogrammetry::CsvTable t =
      photogrammetry::CsvTable::Read(path, {"name", "scan", "x", "y", "z", "e", "n", "h"});
  std::vector<photogrammetry::ScanTarget> out;
  for (const auto& row : t.rows()) {
    photogrammetry::ScanTarget target;
    target.name = t.Text(row, "name");
    const std::string& scan = t.Text(row, "scan");
    target.scan = -1;
    for (size_t i = 0; i < scans.size(); ++i) {
      const std::filesystem::path p(scans[i].path);
      const bool whole_file = scans[i].e57_scan < 0;
      if (scan == scans[i].label || scan == scans[i].stem ||
          (whole_file && (scan == scans[i].path || scan == p.filename().string()))) {
        target.scan = static_cast<int>(i);
      }
    }
    if (target.scan < 0) {
      char* end = nullptr;
      const long index = std::strtol(scan.c_str(), &end, 10);
      if (scan.empty() || *end != '\0' || index < 0 || index >= static_cast<long>(scans.size())) {
        t.Fail(row, "scan", "'" + scan + "' is neither a scan's index (0-" + std::to_string(scans.size() - 1) +
                                ") nor one of the scans' file names");
      }
      target.scan = static_cast<int>(index);
    }
    target.in_scan = {t.Number(row, "x"), t.Number(row, "y"), t.Number(row, "z")};
    target.world = {t.Number(row, "e"), t.Number(row, "n"), t.Number(row, "h")};
    if (t.Has("role")) {
      const std::string& role = t.Text(row, "role");
      if (role == "check") {
        target.role = photogrammetry::TargetRole::kCheck;
      } else if (role != "control" && !role.empty()) {
        t.Fail(row, "role", "'" + role + "'; must be control or check");
      }
    }
    if (t.Has("accuracy")) {
      target.accuracy = t.Number(row, "accuracy");
      if (!(target.accuracy > 0)) t.Fail(row, "accuracy", "must be > 0 (metres)");
    }
    out.push_back(target);
  }
  return out;
}

std::vector<int> ParseIndices(const std::string& text, size_t count) {
  std::vector<int> out;
  if (text.empty()) return out;
  for (double v : ParseNumbers(text, ',', "--fixed")) {
    if (!(v >= 0 && v < static_cast<double>(count)) || v != std::floor(v)) {
      throw std::invalid_argument("--fixed: " + FormatSignificant(v, 6) + " is not a scan index (0-" +
                                  std::to_string(count - 1) + ")");
    }
    out.push_back(static_cast<int>(v));
  }
  return out;
}

// Output names: the scans' stems, made unique with _<index> where two scans share one; the
// extension `format`, else the scan's file's (an E57 scan: .e57, one scan a file).
std::vector<std::string> OutputNames(const std::vector<ScanInput>& scans, const std::string& format) {
  std::vector<std::string> names;
  std::set<std::string> seen, repeated;
  for (const auto& s : scans) {
    if (!seen.insert(s.stem).second) repeated.insert(s.stem);
  }
  for (size_t i = 0; i < scans.size(); ++i) {
    std::string stem = scans[i].stem;
    if (repeated.count(stem)) stem += "_" + std::to_string(i);
    names.push_back(stem + (format.empty() ? std::filesystem::path(scans[i].path).extension().string() : "." + format));
  }
  return names;
}

nlohmann::json Rmse(const photogrammetry::Rmse& r) {
  return {{"count", r.count}, {"x_m", r.x}, {"y_m", r.y}, {"z_m", r.z}, {"xy_m", r.xy}, {"xyz_m", r.d3}};
}

nlohmann::json ReportJson(const std::vector<ScanInput>& inputs, const std::vector<Rigid3>& start,
                          const std::vector<std::string>& names, const std::vector<photogrammetry::ScanTarget>& targets,
                          const MultiRegistrationResult& r, const std::vector<std::string>& start_from) {
  nlohmann::json j;
  j["message"] = r.message;
  j["converged"] = r.converged;
  j["rounds"] = r.outer_iterations;
  j["origin"] = {r.origin.x(), r.origin.y(), r.origin.z()};
  nlohmann::json scans = nlohmann::json::array();
  for (size_t i = 0; i < r.scans.size(); ++i) {
    const auto& s = r.scans[i];
    scans.push_back({{"file", inputs[i].path}, {"e57_scan", inputs[i].e57_scan}, {"label", inputs[i].label},
                     {"output", names[i]}, {"connected", s.connected}, {"fixed", s.fixed},
                     {"world_from_scan", MatrixJson(r.world_from_scan[i])}, {"start", MatrixJson(start[i])},
                     {"start_from", start_from[i]}, {"translation_change_m", s.translation_change},
                     {"rotation_change_deg", s.rotation_change_deg}, {"residual_rms_m", Number(s.residual_rms)},
                     {"correspondences", s.correspondences}});
  }
  j["scans"] = scans;
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& p : r.pairs) {
    pairs.push_back({{"moving", p.moving}, {"fixed", p.fixed}, {"accepted", p.accepted}, {"reason", p.reason},
                     {"overlap", p.overlap}, {"rms_before_m", Number(p.rms_before)},
                     {"rms_after_m", Number(p.rms_after)}, {"rms_global_m", Number(p.rms_global)},
                     {"fixed_from_moving", MatrixJson(p.fixed_from_moving)},
                     {"discrepancy_m", p.discrepancy_translation},
                     {"discrepancy_deg", p.discrepancy_rotation_deg}});
  }
  j["pairs"] = pairs;
  nlohmann::json loops = nlohmann::json::array();
  for (const auto& l : r.loops) {
    loops.push_back({{"scans", l.scans}, {"translation_m", l.translation}, {"rotation_deg", l.rotation_deg}});
  }
  j["loops"] = loops;
  nlohmann::json t = nlohmann::json::array();
  for (size_t i = 0; i < targets.size(); ++i) {
    const Eigen::Vector3d& d = r.target_residuals[i];
    t.push_back({{"name", targets[i].name}, {"scan", targets[i].scan},
                 {"role", photogrammetry::TargetRoleName(targets[i].role)},
                 {"residual_m", {Number(d.x()), Number(d.y()), Number(d.z())}}});
  }
  j["targets"] = t;
  j["control_rmse"] = Rmse(r.control);
  j["check_rmse"] = Rmse(r.check);
  return j;
}

void PrintScans(const std::vector<ScanInput>& inputs, const MultiRegistrationResult& r,
                const std::vector<PointCloud>& scans) {
  std::printf("%-24s %10s %9s %11s %9s %12s\n", "scan", "points", "connected", "moved m", "turned", "residual mm");
  for (size_t i = 0; i < r.scans.size(); ++i) {
    const auto& s = r.scans[i];
    std::printf("%-24s %10zu %9s %11.4f %8.4f° %12.3f\n", std::filesystem::path(inputs[i].label).filename().string().c_str(),
                scans[i].size(), s.fixed ? "fixed" : (s.connected ? "yes" : "NO"), s.translation_change,
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

int RunRegisterScans(const RegisterScansArgs& a) {
  a.options.Check();
  if (a.coarse) a.coarse_options.Check();  // before any scan is read
  if (a.scans.empty()) throw std::invalid_argument("scans: give 2 or more scans");
  const std::vector<ScanInput> inputs = ExpandScans(a.scans);
  if (inputs.size() < 2) throw std::invalid_argument("scans: give 2 or more scans (or an E57 file with several)");
  const std::vector<std::string> names = OutputNames(inputs, a.format);
  for (const auto& n : names) io::OutputPointFormat(n);  // a known extension, before the work
  CheckOutputFolder(a.output_dir);  // its parent exists; the folder is made when writing
  const auto start_time = std::chrono::steady_clock::now();
  photogrammetry::MultiRegistrationOptions options = a.options;
  options.fixed_scans = ParseIndices(a.fixed, inputs.size());
  std::vector<Rigid3> start(inputs.size());
  // Where each scan's start pose came from (registration.json's start_from).
  const std::string kNoStart = "identity (no start pose)";
  std::vector<std::string> start_from(inputs.size(), kNoStart);
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].has_pose) {
      start[i] = inputs[i].pose;
      start_from[i] = "stored in the E57 file";
    }
  }
  if (!a.poses.empty()) {
    start = ReadStartPoses(a.poses, inputs.size());
    start_from.assign(inputs.size(), "given (--poses)");
  }
  const std::vector<photogrammetry::ScanTarget> targets =
      a.targets.empty() ? std::vector<photogrammetry::ScanTarget>() : ReadScanTargets(a.targets, inputs);
  std::vector<PointCloud> scans;
  for (const auto& in : inputs) scans.push_back(ReadScan(in));
  if (a.coarse) {
    start_from[0] = "anchor of the coarse alignment (" + start_from[0] + ")";
    for (size_t i = 1; i < scans.size(); ++i) {
      if (start_from[i] != kNoStart) continue;  // it has a start pose
      const auto c = photogrammetry::CoarseAlign(a.coarse_options, scans[i], scans[0]);
      start_from[i] = "coarse alignment onto scan 0: " + c.message;
      if (c.found) start[i] = start[0] * c.fixed_from_moving;  // scan i -> scan 0 -> world
      std::printf("coarse %s onto %s: %s\n", inputs[i].label.c_str(), inputs[0].label.c_str(), c.message.c_str());
    }
  }
  MultiRegistrationResult result;
  {
    ConsoleProgressOptions po;
    po.unit = "steps";
    ConsoleProgress progress("register " + std::to_string(scans.size()) + " scans", po);
    result = photogrammetry::RegisterScans(options, scans, start, targets, progress.Callback());
  }
  PrintScans(inputs, result, scans);
  std::filesystem::create_directories(a.output_dir);
  for (size_t i = 0; i < scans.size(); ++i) {
    io::WritePointCloud(a.output_dir + "/" + names[i],
                        photogrammetry::TransformPointCloud(result.world_from_scan[i], scans[i]));
  }
  WriteFileAtomic(a.output_dir + "/registration.json",
                  ReportJson(inputs, start, names, targets, result, start_from).dump(2) + "\n");
  std::printf("wrote %zu scans and registration.json to %s, time %.2f s\n", scans.size(), a.output_dir.c_str(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count());
  size_t unconnected = 0;
  for (const auto& s : result.scans) unconnected += s.connected ? 0 : 1;
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
