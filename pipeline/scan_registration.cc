#include "pipeline/scan_registration.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/csv_table.h"
#include "io/e57/e57_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/registration/local_points.h"

namespace candi::pipeline {

namespace {

namespace pg = candi::photogrammetry;
using Clock = std::chrono::steady_clock;

double SecondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json MatrixJson(const Rigid3& t) {
  const Eigen::Matrix4d m = t.ToMatrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  return rows;
}

// The rigid transform a 4x4 holds (hand-written matrices: 4-5 digits); `where` names it in errors.
Rigid3 RigidOf(const Eigen::Matrix4d& t, const std::string& path, const std::string& where) {
  try {
    const Sim3 s = Sim3FromMatrix(t, 1e-4);
    if (std::abs(s.scale - 1.0) > 1e-4) throw std::invalid_argument("scale is not 1");
    return Rigid3(s.rotation, s.translation);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, where, "not a rigid transform: " + std::string(e.what()));
  }
}

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
  return RigidOf(t, path, "fixed_from_moving");
}

PointCloud ReadInput(const std::string& path) {
  PointCloud cloud = io::ReadPointCloud(path);
  if (cloud.empty()) throw InputError(path, "", "no points");
  pg::CheckFinitePositions(cloud, path);
  return cloud;
}

void WriteTransformJson(const RegisterPairOptions& o, const std::string& moving,
                        const std::string& fixed, const pg::RegistrationResult& r) {
  const nlohmann::json j = {{"fixed_from_moving", MatrixJson(r.fixed_from_moving)},
                            {"moving", moving},
                            {"fixed", fixed},
                            {"status", pg::RegistrationStatusName(r.status)},
                            {"message", r.message},
                            {"method", pg::IcpMethodName(r.method)},
                            {"iterations", r.iterations},
                            {"max_distance_m", o.icp.max_correspondence_distance},
                            {"rms_before_m", Number(r.rms_before)},
                            {"rms_after_m", Number(r.rms_after)},
                            {"overlap_before", r.overlap_before},
                            {"overlap_after", r.overlap_after}};
  WriteFileAtomic(o.transform_out, j.dump(2) + "\n");
}

}  // namespace

void RegisterPairOptions::Check() const { icp.Check(); }

RegisteredPair RegisterPair(const RegisterPairOptions& o, const std::string& moving_path,
                            const std::string& fixed_path, const std::string& output,
                            const RegisterPairCallbacks& callbacks) {
  o.Check();  // bad values: std::invalid_argument, exit 1
  pg::RegistrationOptions options = o.icp;
  io::OutputPointFormat(output);  // a known extension, before the work
  CheckOutputFolder(output);
  if (!o.transform_out.empty()) CheckOutputFolder(o.transform_out);
  if (!o.initial.empty()) options.initial = ReadTransform(o.initial);
  const auto start = Clock::now();
  const PointCloud moving = ReadInput(moving_path);
  const PointCloud fixed = ReadInput(fixed_path);
  RegisteredPair out;
  {
    ProgressTask task(callbacks.progress, "ICP", "iterations");
    out.result = pg::RegisterPointClouds(options, moving, fixed, task.callback());
  }
  const pg::RegistrationResult& r = out.result;
  if (callbacks.registered) callbacks.registered(r);
  if (!o.transform_out.empty()) WriteTransformJson(o, moving_path, fixed_path, r);
  if (r.status == pg::RegistrationStatus::kNoOverlap) {
    throw InputError(moving_path, "", "cannot be registered onto " + fixed_path + ": " + r.message);
  }
  io::WritePointCloud(output, pg::TransformPointCloud(r.fixed_from_moving, moving));
  out.points = moving.size();
  out.seconds = SecondsSince(start);
  return out;
}

namespace {

// A 4x4 rigid transform from JSON (`where` names it in errors).
Rigid3 RigidFromJson(const nlohmann::json& m, const std::string& path, const std::string& where) {
  Eigen::Matrix4d t;
  if (!m.is_array() || m.size() != 4)
    throw InputError(path, where, "expected a 4x4 array of numbers");
  for (int r = 0; r < 4; ++r) {
    if (!m[r].is_array() || m[r].size() != 4)
      throw InputError(path, where, "expected a 4x4 array of numbers");
    for (int c = 0; c < 4; ++c) {
      if (!m[r][c].is_number()) throw InputError(path, where, "expected a 4x4 array of numbers");
      t(r, c) = m[r][c].get<double>();
    }
  }
  return RigidOf(t, path, where);
}

// Start poses: a JSON array of 4x4 world_from_scan (one per scan), or a registration.json whose
// "scans" hold them.
std::vector<Rigid3> ReadStartPoses(const std::string& path, size_t count) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(ReadFileToString(path));
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, "", "not JSON: " + std::string(e.what()));
  }
  std::vector<nlohmann::json> matrices;
  if (j.is_object() && j.contains("scans") && j["scans"].is_array()) {
    for (const auto& s : j["scans"])
      matrices.push_back(s.value("world_from_scan", nlohmann::json()));
  } else if (j.is_array()) {
    for (const auto& m : j) matrices.push_back(m);
  } else {
    throw InputError(path, "", "expected an array of 4x4 matrices, or a registration.json");
  }
  if (matrices.size() != count) {
    throw InputError(path, "",
                     "holds " + std::to_string(matrices.size()) + " poses for " +
                         std::to_string(count) + " scans");
  }
  std::vector<Rigid3> poses;
  for (size_t i = 0; i < count; ++i)
    poses.push_back(RigidFromJson(matrices[i], path, "pose " + std::to_string(i)));
  return poses;
}

// The files as scans: an E57 file with several scans counts as that many, each starting from
// its stored pose.
std::vector<ScanInput> ExpandScans(const std::vector<std::string>& files) {
  std::vector<ScanInput> out;
  for (const std::string& f : files) {
    const std::filesystem::path p(f);
    std::string ext = p.extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const std::vector<io::E57ScanInfo> e57 =
        ext == ".e57" ? io::ListE57Scans(f) : std::vector<io::E57ScanInfo>();
    if (e57.size() <= 1) {
      out.push_back({f, -1, f, p.stem().string(), false, Rigid3()});
      continue;
    }
    for (size_t k = 0; k < e57.size(); ++k) {
      ScanInput in{f,
                   static_cast<int>(k),
                   f + "#" + std::to_string(k) + " (" + e57[k].name + ")",
                   p.stem().string() + "_" + std::to_string(k),
                   true,
                   Rigid3(e57[k].rotation, e57[k].translation)};
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
  pg::CheckFinitePositions(cloud, in.label);
  return cloud;
}

// The index of the scan a target's `scan` names: by its label or output stem, by the file's
// path or name (a whole file), else by index (the table's error naming the row otherwise).
int TargetScan(const io::CsvTable& t, const io::CsvTable::Row& row,
               const std::vector<ScanInput>& scans) {
  const std::string& scan = t.Text(row, "scan");
  int found = -1;
  for (size_t i = 0; i < scans.size(); ++i) {
    const std::filesystem::path p(scans[i].path);
    const bool whole_file = scans[i].e57_scan < 0;
    if (scan == scans[i].label || scan == scans[i].stem ||
        (whole_file && (scan == scans[i].path || scan == p.filename().string()))) {
      found = static_cast<int>(i);
    }
  }
  if (found >= 0) return found;
  char* end = nullptr;
  const long index = std::strtol(scan.c_str(), &end, 10);
  if (scan.empty() || *end != '\0' || index < 0 || index >= static_cast<long>(scans.size())) {
    t.Fail(row, "scan",
           "'" + scan + "' is neither a scan's index (0-" + std::to_string(scans.size() - 1) +
               ") nor one of the scans' file names");
  }
  return static_cast<int>(index);
}

// Targets CSV: name,scan,x,y,z,E,N,H[,role[,accuracy]]; scan by index, by file name or stem, or
// (an E57's scan) by its label "file#k" or output stem "stem_k".
std::vector<pg::ScanTarget> ReadScanTargets(const std::string& path,
                                            const std::vector<ScanInput>& scans) {
  const io::CsvTable t = io::CsvTable::Read(path, {"name", "scan", "x", "y", "z", "e", "n", "h"});
  std::vector<pg::ScanTarget> out;
  for (const auto& row : t.rows()) {
    pg::ScanTarget target;
    target.name = t.Text(row, "name");
    target.scan = TargetScan(t, row, scans);
    target.in_scan = {t.Number(row, "x"), t.Number(row, "y"), t.Number(row, "z")};
    target.world = {t.Number(row, "e"), t.Number(row, "n"), t.Number(row, "h")};
    if (t.Has("role")) {
      const std::string& role = t.Text(row, "role");
      if (role == "check") {
        target.role = pg::TargetRole::kCheck;
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
      throw std::invalid_argument("--fixed: " + FormatSignificant(v, 6) +
                                  " is not a scan index (0-" + std::to_string(count - 1) + ")");
    }
    out.push_back(static_cast<int>(v));
  }
  return out;
}

// Output names: the scans' stems, made unique with _<index> where two scans share one; the
// extension `format`, else the scan's file's (an E57 scan: .e57, one scan a file).
std::vector<std::string> OutputNames(const std::vector<ScanInput>& scans,
                                     const std::string& format) {
  std::vector<std::string> names;
  std::set<std::string> seen, repeated;
  for (const auto& s : scans) {
    if (!seen.insert(s.stem).second) repeated.insert(s.stem);
  }
  for (size_t i = 0; i < scans.size(); ++i) {
    std::string stem = scans[i].stem;
    if (repeated.count(stem)) stem += "_" + std::to_string(i);
    names.push_back(stem + (format.empty()
                                ? std::filesystem::path(scans[i].path).extension().string()
                                : "." + format));
  }
  return names;
}

nlohmann::json Rmse(const pg::Rmse& r) {
  return {{"count", r.count}, {"x_m", r.x},   {"y_m", r.y},
          {"z_m", r.z},       {"xy_m", r.xy}, {"xyz_m", r.d3}};
}

nlohmann::json ScansJson(const RegisteredScans& s, const std::vector<Rigid3>& start,
                         const std::vector<std::string>& start_from) {
  const pg::MultiRegistrationResult& r = s.result;
  nlohmann::json scans = nlohmann::json::array();
  for (size_t i = 0; i < r.scans.size(); ++i) {
    const auto& report = r.scans[i];
    const ScanInput& in = s.scans[i];
    // clang-format off
    scans.push_back({{"file", in.path}, {"e57_scan", in.e57_scan}, {"label", in.label},
                     {"output", s.outputs[i]}, {"connected", report.connected}, {"fixed", report.fixed},
                     {"world_from_scan", MatrixJson(r.world_from_scan[i])}, {"start", MatrixJson(start[i])},
                     {"start_from", start_from[i]}, {"translation_change_m", report.translation_change},
                     {"rotation_change_deg", report.rotation_change_deg},
                     {"residual_rms_m", Number(report.residual_rms)}, {"correspondences", report.correspondences}});
    // clang-format on
  }
  return scans;
}

// registration.json: the outcome, each scan (its start and where it came from), pair, loop and
// target, and the targets' RMSE.
nlohmann::json ReportJson(const RegisteredScans& s, const std::vector<Rigid3>& start,
                          const std::vector<pg::ScanTarget>& targets,
                          const std::vector<std::string>& start_from) {
  const pg::MultiRegistrationResult& r = s.result;
  nlohmann::json j;
  j["message"] = r.message;
  j["converged"] = r.converged;
  j["rounds"] = r.outer_iterations;
  j["origin"] = {r.origin.x(), r.origin.y(), r.origin.z()};
  j["scans"] = ScansJson(s, start, start_from);
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& p : r.pairs) {
    // clang-format off
    pairs.push_back({{"moving", p.moving}, {"fixed", p.fixed}, {"accepted", p.accepted}, {"reason", p.reason},
                     {"overlap", p.overlap}, {"rms_before_m", Number(p.rms_before)},
                     {"rms_after_m", Number(p.rms_after)}, {"rms_global_m", Number(p.rms_global)},
                     {"fixed_from_moving", MatrixJson(p.fixed_from_moving)},
                     {"discrepancy_m", p.discrepancy_translation},
                     {"discrepancy_deg", p.discrepancy_rotation_deg}});
    // clang-format on
  }
  j["pairs"] = pairs;
  nlohmann::json loops = nlohmann::json::array();
  for (const auto& l : r.loops) {
    loops.push_back(
        {{"scans", l.scans}, {"translation_m", l.translation}, {"rotation_deg", l.rotation_deg}});
  }
  j["loops"] = loops;
  nlohmann::json t = nlohmann::json::array();
  for (size_t i = 0; i < targets.size(); ++i) {
    const Eigen::Vector3d& d = r.target_residuals[i];
    t.push_back({{"name", targets[i].name},
                 {"scan", targets[i].scan},
                 {"role", pg::TargetRoleName(targets[i].role)},
                 {"residual_m", {Number(d.x()), Number(d.y()), Number(d.z())}}});
  }
  j["targets"] = t;
  j["control_rmse"] = Rmse(r.control);
  j["check_rmse"] = Rmse(r.check);
  return j;
}

// Where each scan's start pose comes from (registration.json's start_from), without a coarse
// alignment.
const char kNoStart[] = "identity (no start pose)";

// The start poses: identity, an E57 scan's stored pose, or the given file's; `start_from` says
// which.
std::vector<Rigid3> StartPoses(const RegisterScansOptions& o, const std::vector<ScanInput>& inputs,
                               std::vector<std::string>* start_from) {
  std::vector<Rigid3> start(inputs.size());
  start_from->assign(inputs.size(), kNoStart);
  for (size_t i = 0; i < inputs.size(); ++i) {
    if (inputs[i].has_pose) {
      start[i] = inputs[i].pose;
      (*start_from)[i] = "stored in the E57 file";
    }
  }
  if (!o.poses.empty()) {
    start = ReadStartPoses(o.poses, inputs.size());
    start_from->assign(inputs.size(), "given (--poses)");
  }
  return start;
}

// Scans without a start pose, coarsely aligned onto scan 0 (their start: where it puts them).
void CoarseStarts(const RegisterScansOptions& o, const std::vector<ScanInput>& inputs,
                  const std::vector<PointCloud>& scans, const RegisterScansCallbacks& callbacks,
                  std::vector<Rigid3>* start, std::vector<std::string>* start_from) {
  (*start_from)[0] = "anchor of the coarse alignment (" + (*start_from)[0] + ")";
  for (size_t i = 1; i < scans.size(); ++i) {
    if ((*start_from)[i] != kNoStart) continue;  // it has a start pose
    const auto c = pg::CoarseAlign(o.coarse_options, scans[i], scans[0]);
    (*start_from)[i] = "coarse alignment onto scan 0: " + c.message;
    if (c.found) (*start)[i] = (*start)[0] * c.fixed_from_moving;  // scan i -> scan 0 -> world
    if (callbacks.coarse) callbacks.coarse(inputs[i], inputs[0], c.message);
  }
}

}  // namespace

void RegisterScansOptions::Check() const {
  registration.Check();
  if (coarse) coarse_options.Check();
}

RegisteredScans RegisterScanFiles(const RegisterScansOptions& o,
                                  const std::vector<std::string>& files,
                                  const std::string& output_dir,
                                  const RegisterScansCallbacks& callbacks) {
  o.Check();  // before any scan is read
  if (files.empty()) throw std::invalid_argument("scans: give 2 or more scans");
  RegisteredScans out;
  out.scans = ExpandScans(files);
  const std::vector<ScanInput>& inputs = out.scans;
  if (inputs.size() < 2)
    throw std::invalid_argument("scans: give 2 or more scans (or an E57 file with several)");
  out.outputs = OutputNames(inputs, o.format);
  for (const auto& n : out.outputs) io::OutputPointFormat(n);  // a known extension, before the work
  CheckOutputFolder(output_dir);  // its parent exists; the folder is made when writing
  const auto start_time = Clock::now();
  pg::MultiRegistrationOptions options = o.registration;
  options.fixed_scans = ParseIndices(o.fixed, inputs.size());
  std::vector<std::string> start_from;
  std::vector<Rigid3> start = StartPoses(o, inputs, &start_from);
  const std::vector<pg::ScanTarget> targets =
      o.targets.empty() ? std::vector<pg::ScanTarget>() : ReadScanTargets(o.targets, inputs);
  std::vector<PointCloud> scans;
  for (const auto& in : inputs) scans.push_back(ReadScan(in));
  for (const PointCloud& s : scans) out.points.push_back(s.size());
  if (o.coarse) CoarseStarts(o, inputs, scans, callbacks, &start, &start_from);
  {
    ProgressTask task(callbacks.progress, "register " + std::to_string(scans.size()) + " scans",
                      "steps");
    out.result = pg::RegisterScans(options, scans, start, targets, task.callback());
  }
  if (callbacks.registered) callbacks.registered(out);
  std::filesystem::create_directories(output_dir);
  for (size_t i = 0; i < scans.size(); ++i) {
    io::WritePointCloud(output_dir + "/" + out.outputs[i],
                        pg::TransformPointCloud(out.result.world_from_scan[i], scans[i]));
  }
  WriteFileAtomic(output_dir + "/registration.json",
                  ReportJson(out, start, targets, start_from).dump(2) + "\n");
  out.seconds = SecondsSince(start_time);
  return out;
}

}  // namespace candi::pipeline
