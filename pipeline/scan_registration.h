// `candi register` and `candi register-scans`: scans registered from their files to the moved
// files and the report (photogrammetry/registration/registration.h, multi_registration.h).
//
// RegisterPair: MOVING refined onto FIXED by ICP, from an optional initial transform (JSON), and
// written moved, in its own format, precision and shift, with the transform and its figures as
// JSON when asked. RegisterScanFiles: many scans into one frame at once. An E57 file of several
// scans counts as that many, each starting from its stored pose; start poses may be given (4x4
// world_from_scan in JSON, or an earlier registration.json), or found by coarse alignment onto scan
// 0 (FPFH + RANSAC) for scans without one; targets seen in the scans (CSV) tie them to the survey.
// The moved scans and registration.json are written into the output folder.
// World coordinates (each file's shift applied). Failures: std::invalid_argument for invalid
// options (the scans `fixed` names among them), InputError naming the file for unreadable or
// malformed inputs, unwritable outputs, and a pair that does not overlap. Library
// candi_pipeline_pcl (PCL), linked only by candi-pcl and candi-relief.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/task_progress.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/registration/coarse_alignment.h"
#include "reconstruction/photogrammetry/registration/multi_registration.h"
#include "reconstruction/photogrammetry/registration/registration.h"

namespace candi::pipeline {

struct RegisterPairOptions {
  photogrammetry::RegistrationOptions icp;  // its `initial` is read from `initial`, when given
  std::string initial;  // optional JSON: the initial fixed_from_moving (as transform_out writes)
  std::string transform_out;  // optional JSON: the 4x4 fixed_from_moving and the figures
  void Check() const;
};

struct RegisteredPair {
  photogrammetry::RegistrationResult result;
  size_t points = 0;   // the moving file's points, written moved
  double seconds = 0;  // from reading the files to the moved file written
};

struct RegisterPairCallbacks {
  TaskProgress progress;  // the ICP ("ICP", in iterations)
  // Once registered, before anything is written (also when the clouds do not overlap).
  std::function<void(const photogrammetry::RegistrationResult&)> registered;
};

// `moving` registered onto `fixed`, written moved to `output`. A registration that did not
// converge is written (the last transform applied; result.status says so); one that found no
// overlap is an InputError after `registered`, with nothing but the transform JSON written.
RegisteredPair RegisterPair(const RegisterPairOptions& options, const std::string& moving,
                            const std::string& fixed, const std::string& output,
                            const RegisterPairCallbacks& callbacks = {});

struct RegisterScansOptions {
  photogrammetry::MultiRegistrationOptions registration;  // its fixed_scans are `fixed`'s
  // "0,2": scans held at their start pose, by index, an E57 file's scans counted one by one
  // (checked once the files are opened; named --fixed in messages).
  std::string fixed;
  std::string poses;  // optional JSON: start poses world_from_scan, or an earlier registration.json
  std::string targets;  // optional CSV: name,scan,x,y,z,E,N,H[,role[,accuracy]]
  bool coarse = false;  // scans without a start pose: coarse alignment onto scan 0 first
  photogrammetry::CoarseAlignmentOptions coarse_options;
  std::string format;  // the moved scans' extension ("" = each scan's own)
  void Check() const;
};

// One scan to register: a point file, or one scan of an E57 file that holds several.
struct ScanInput {
  std::string path;
  int e57_scan = -1;  // >= 0: this scan of the E57 file, read in its own frame
  std::string label;  // how it is named: the file, or "file#k (name)" for an E57's scan k
  std::string stem;   // the output's name without extension
  bool has_pose = false;
  Rigid3 pose;  // an E57 scan's stored pose: its start
};

struct RegisteredScans {
  std::vector<ScanInput> scans;      // an E57 file's scans one by one
  std::vector<size_t> points;        // each scan's points
  std::vector<std::string> outputs;  // the moved scans' file names in the output folder
  photogrammetry::MultiRegistrationResult result;
  double seconds = 0;  // from the checks of the outputs to registration.json written
};

struct RegisterScansCallbacks {
  TaskProgress progress;  // the registration ("register N scans", in steps)
  // Each coarse alignment as it ends: the scan, the anchor (scan 0) and what was found.
  std::function<void(const ScanInput& moving, const ScanInput& anchor, const std::string& message)>
      coarse;
  // Once registered, before anything is written.
  std::function<void(const RegisteredScans&)> registered;
};

// The scans of `files` registered; the moved scans and registration.json written into
// `output_dir` (made; its parent must exist).
RegisteredScans RegisterScanFiles(const RegisterScansOptions& options,
                                  const std::vector<std::string>& files,
                                  const std::string& output_dir,
                                  const RegisterScansCallbacks& callbacks = {});

}  // namespace candi::pipeline
