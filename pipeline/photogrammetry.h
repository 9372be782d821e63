// The standing building from photographs: COLMAP structure from motion into a dense workspace,
// candi's CPU PatchMatch stereo and fusion into coloured points, and georeferencing on surveyed
// targets (reconstruction/photogrammetry). What `candi sfm`, `candi dense` and `candi georef` do
// (GeoreferenceFiles: the fit and the files it moves), and a build's photogrammetry layer, which
// passes the points between them in memory.
// Units: metres, pixels; the model's frame until georeferenced, the survey frame (its integer
// shift, GeorefResult::frame) after. Failures: std::invalid_argument for invalid options,
// InputError naming the file (or COLMAP's exit code and log) otherwise; a fit that does not
// converge is a result (GeorefResult::fit), not an error. Not thread-safe (runs processes).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/point_cloud.h"
#include "reconstruction/photogrammetry/georef/georef.h"
#include "reconstruction/photogrammetry/georef/georef_colmap.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/mvs/dense_stream.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"

namespace candi::pipeline {

// How a photogrammetry layer's model is made reproducible (recorded in sfm_report.json and a
// build's archive.json).
inline constexpr const char* kSfmReproducibility =
    "image ids by photo name; exact matching (same matches every run, any thread count); COLMAP matches_importer "
    "and mapper on one thread, random_seed 0: the same photos and options give the same model bytes on this machine";

// COLMAP structure from motion of the photos in `images` into `workspace` (colmap_runner.h);
// each stage's progress on stderr, warnings for photos without EXIF or not registered, and
// WORKSPACE/sfm_report.json (what ran, the model's figures, the stage times).
// `run_mappers`: who runs the chunk mappers (nullptr: this process; pipeline/sfm_ranks.h: the ranks).
photogrammetry::SfmSummary StructureFromMotion(const photogrammetry::SfmOptions& options, const std::string& images,
                                               const std::string& workspace,
                                               const photogrammetry::ChunkMapperRunner& run_mappers = nullptr);

struct DenseOptions {
  photogrammetry::PatchMatchOptions stereo;
  photogrammetry::FusionOptions fusion;
  uint64_t max_memory = 0;  // bytes of images and maps held at once; 0 = a quarter of the machine's
  // Depth and normal maps stay in WORKSPACE/stereo/ (COLMAP's arrays for its stereo_fusion, and
  // candi's resume files); false: they are removed once the run has finished.
  bool write_maps = true;
  void Check() const;
};

using DenseCloud = photogrammetry::DenseStreamResult;

// This process's share under mpirun (pipeline/dense_ranks.h); the default is the whole run.
struct DenseRankShare {
  int rank = 0, ranks = 1;
  std::function<std::vector<std::string>(const std::string&)> all_gather;  // collective
  // Rank 0's points, cell by cell, instead of the result's cloud (DenseStreamOptions::cells_out).
  std::function<void(const PointCloud& cell)> cells_out;
};

// The comment a dense cloud carries: "candi dense WORKSPACE".
std::string DenseComment(const std::string& workspace);

// PatchMatch stereo on a COLMAP dense workspace (images/ + sparse/, PINHOLE cameras) and fusion,
// streamed and resumable (photogrammetry/mvs/dense_stream.h).
DenseCloud DenseStereo(const DenseOptions& options, const std::string& workspace, const DenseRankShare& share = {});

struct GeorefOptions {
  photogrammetry::SimilarityFitOptions fit;
  std::string crs;          // the survey frame's CRS (stated in the outputs); "" none
  std::string targets_crs;  // the targets' CRS, transformed into `crs` with PROJ first; "" = crs
  void Check() const;
};

// The targets of `targets_csv` (transformed into options.crs when targets_crs is given),
// triangulated from `picks_csv` (when given) in the cameras of `model` (a COLMAP model read by
// photogrammetry::ReadColmapForGeoref; required with picks), and the robust similarity fit.
photogrammetry::GeorefResult FitGeoref(const GeorefOptions& options, const std::string& targets_csv,
                                       const photogrammetry::ColmapGeorefInput* model, const std::string& picks_csv);

// `cloud` (the model's frame) moved into the survey frame (result.frame), stating options.crs.
void Georeference(const GeorefOptions& options, const photogrammetry::GeorefResult& result, PointCloud* cloud);

// The fit as JSON (OUT.georef.json): the transform, the shift, the loss, convergence, warnings,
// per-target residuals and the RMSE of control and check targets.
nlohmann::json GeorefReport(const GeorefOptions& options, const photogrammetry::GeorefResult& result);

// What `candi georef` reads and writes.
struct GeorefFiles {
  std::string input;    // a point file, or a COLMAP sparse model folder
  std::string targets;  // the targets CSV (photogrammetry/georef/georef.h)
  std::string model;    // the COLMAP sparse model the picks are in ("": `input`, when it is a model)
  std::string picks;    // optional picks CSV: name,image,u,v
  std::string output;   // a point file (for a point file in) or a folder (for a model), and OUTPUT.georef.json
};

// `candi georef`: the fit (FitGeoref), then the input moved into the survey frame: a point file
// streamed through the transform into `output` (its fields kept, options.crs stated), or a model
// into the folder `output` with its points (points.ply); then OUTPUT.georef.json (GeorefReport).
// `fitted` (may be null) gets the fit before anything is written; its warnings are logged. A fit
// that does not converge is written and reported, not an error.
photogrammetry::GeorefResult GeoreferenceFiles(
    const GeorefOptions& options, const GeorefFiles& files,
    const std::function<void(const photogrammetry::GeorefResult&)>& fitted = nullptr);

}  // namespace candi::pipeline
