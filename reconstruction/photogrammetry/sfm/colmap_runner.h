// Structure from motion with COLMAP run as child processes: a folder of photos in, a COLMAP sparse
// model and an undistorted dense workspace out.
//
// Layout of WORKSPACE after RunSfm:
//   images/          symlinks to the input photos (COLMAP wants a folder holding only images)
//   chunks/<c>.txt   mapped in chunks: each chunk's image list; sparse_chunks/<c>/ its models;
//                    sparse/merged/ the tied chunks in the targets' local frame
//   database.db      COLMAP's features and matches
//   sparse/<k>/      the mapper's models (the largest is the result)
//   dense/           COLMAP's dense workspace: images/ (undistorted), sparse/ (PINHOLE model),
//                    stereo/ (empty depth/normal folders), run scripts
//   logs/<stage>.log stdout + stderr of each COLMAP stage
//   sfm_stages.txt   what the outputs depend on and the stages (chunks) finished: --resume
//                    continues from there, an unfinished stage started again from nothing
//
// COLMAP is started with an argv vector (posix_spawnp, never a shell), so paths with spaces or
// shell characters are safe. Failure: InputError when COLMAP is missing, the input folder is
// unusable, a stage fails (its exit code and the end of its log) or no model results.
// Not thread-safe with respect to the workspace; one run per workspace.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "reconstruction/photogrammetry/sfm/chunked_mapping.h"
#include "reconstruction/photogrammetry/sfm/pair_selection.h"

namespace candi::photogrammetry {

// What `colmap help` says about itself.
struct ColmapVersion {
  std::string version;  // "3.8", "" when not recognised
  bool cuda = false;    // built with CUDA ("with CUDA" rather than "without CUDA")
};
// Parses `colmap help`'s banner ("COLMAP 3.8 -- Structure-from-Motion ... without CUDA)").
// Throws std::invalid_argument when the text is not a COLMAP banner.
ColmapVersion ParseColmapVersion(const std::string& help_output);

struct SfmOptions {
  std::string colmap = "colmap";      // the executable: a path, or a name looked up on PATH
  int max_image_size = 1600;          // pixels, the longest side for SIFT and the dense images, >= 64
  int max_features = 4096;            // SIFT features per image, >= 64
  PairSelectionOptions pairs;         // which pairs are matched (pair_selection.h)
  std::string priors;                 // GPS-like camera positions (priors.csv, name,E,N,H); "" = none
  ChunkedMappingOptions chunks;       // with targets: each session folder mapped apart, then tied
  std::string camera_model = "SIMPLE_RADIAL";  // a COLMAP camera model name
  bool single_camera = true;          // one camera (intrinsics) shared by all photos
  int threads = -1;                   // feature extraction and matching threads; -1 = all cores, else >= 1
  bool overwrite = false;             // replace a previous run's outputs in the workspace
  bool resume = false;                // continue a stopped run: its finished stages and chunks are kept
  void Check() const;
};

// One COLMAP invocation.
struct SfmStage {
  std::string name;               // "feature_extractor", ... (also the log's name)
  std::vector<std::string> argv;  // argv[0] is the executable
};

// The stage run in candi itself, not by COLMAP (its argv is empty): exact matching of the
// extracted features into WORKSPACE/matches.txt (sift_matching.h).
inline constexpr const char* kMatchStage = "match_features";
// candi's second in-process stage, after COLMAP's verification: rounds of transitive matching
// (pair_selection.h), each round's pairs matched into WORKSPACE/transitive_matches/round_<r>.txt
// and verified by COLMAP as the first pairs were. Nothing to do after exhaustive matching.
inline constexpr const char* kTransitiveStage = "transitive_matching";
inline constexpr const char* kTransitiveFolder = "transitive_matches";

// The stages for a workspace (absolute paths inside it): feature_extractor, match_features
// (candi's), matches_importer (COLMAP's geometric verification of those matches, one thread),
// transitive_matching (candi's, with COLMAP's verification), mapper (one thread, seeded) and image_undistorter, whose --input_path is a placeholder
// (`<model>`) that RunSfm replaces with the largest model's folder. `cuda` keeps the GPU on for
// SIFT extraction. Everything after extraction runs on one thread or exactly, so the same photos
// and options give the same model bytes (README, "Reproducibility").
std::vector<SfmStage> BuildSfmStages(const SfmOptions& options, const std::string& workspace, bool cuda);

// Progress of a run: called when a stage starts (done = false, seconds = 0), every few seconds
// while it runs (done = false) and when it ends (done = true). seconds = elapsed in the stage;
// fraction = how much of the stage is done, 0 to 1, from its own count (COLMAP's "[i/N]" and
// "Registering image #k (n)" in its log, candi's pairs and chunks), -1 where it gives none.
using SfmProgress = std::function<void(const std::string& stage, int index, int count,
                                       double seconds, bool done, double fraction)>;

struct SfmSummary {
  ColmapVersion colmap;
  std::vector<std::string> images;        // photo file names used (sorted)
  std::vector<std::string> ignored;       // non-image files skipped in the input folder
  std::vector<std::string> registered;    // names of the photos in the model
  std::vector<std::string> no_exif;       // photos whose focal length was guessed (no EXIF prior)
  double default_focal_px = 0;            // the guessed focal, pixels (0 when all had EXIF)
  std::vector<std::string> unreadable;    // files COLMAP could not decode (skipped)
  std::vector<std::string> other_size;    // one camera shared: photos of another size than the first (skipped)
  std::vector<std::pair<std::string, double>> focal_priors;  // photo, EXIF focal in pixels (sorted by name)
  std::vector<std::pair<std::string, std::string>> duplicates;  // a photo left out, the same bytes as the kept one
  size_t points = 0;                      // sparse points
  double mean_reprojection_error = 0;     // pixels, COLMAP's definition
  double mean_track_length = 0;           // observations per point
  std::string matcher;                    // how pairs were chosen (PairSelection::strategy)
  size_t pairs_tried = 0;                 // pairs matched
  size_t pairs_verified = 0;              // pairs COLMAP's geometric verification kept
  std::string model_dir;                  // WORKSPACE/sparse/<k>, the largest model (chunks: sparse/merged)
  ChunkedMappingResult chunked;           // mapped in chunks: each chunk, their consistency, the shift
  std::string dense_dir;                  // WORKSPACE/dense
  std::vector<std::pair<std::string, double>> stage_seconds;
};

// One chunk's COLMAP mapper (mapping in chunks): its argv and the log it writes.
struct ChunkMapperJob {
  std::string chunk;              // the session folder's name
  std::vector<std::string> argv;  // argv[0] is COLMAP
  std::string log;                // WORKSPACE/logs/mapper_<chunk>.log
};
// Runs the chunk mappers and returns one error text a job ("" when it ran; a mapper that found no
// model ran: its chunk is reported untied). The default runs `parallel` at once in this process;
// under mpirun the ranks share them (pipeline/sfm_ranks.h). Every job gives the same model bytes
// whoever runs it.
using ChunkMapperRunner = std::function<std::vector<std::string>(const std::vector<ChunkMapperJob>& jobs)>;
// Runs the jobs for which `mine(index)` holds (all when nullptr), `parallel` at once; the errors
// of the others stay "". `by` (e.g. "rank 1 of 2"), when given, heads each log; `finished` is
// told which job ended and how many have, after each (one call at a time).
std::vector<std::string> RunChunkMappers(const std::vector<ChunkMapperJob>& jobs, int parallel,
                                         const std::function<bool(size_t)>& mine = nullptr,
                                         const std::string& by = "",
                                         const std::function<void(size_t job, size_t finished)>& finished = nullptr);

// Runs feature extraction, matching, mapping and undistortion. See the file comment.
// `run_mappers`: who runs the chunk mappers (nullptr: RunChunkMappers, options.chunks.parallel).
SfmSummary RunSfm(const SfmOptions& options, const std::string& images_dir,
                  const std::string& workspace, const SfmProgress& progress = nullptr,
                  const ChunkMapperRunner& run_mappers = nullptr);

// Lower-level pieces, exposed for tests.
// Image files (by extension, case-insensitive: jpg jpeg png tif tiff bmp pgm ppm pnm) directly in
// `dir`, sorted; other regular files go to `ignored`. A folder that holds no image itself but
// subfolders that do (a campaign's sessions) gives theirs, named "folder/file", in name order.
// Throws InputError for a missing folder.
std::vector<std::string> ListImages(const std::string& dir, std::vector<std::string>* ignored);
// Runs argv with stdout and stderr appended to log_path; returns the exit code (128 + signal when
// killed). Throws InputError naming argv[0] when it cannot be started (not found, not executable).
int RunLogged(const std::vector<std::string>& argv, const std::string& log_path,
              const std::function<void(double seconds)>& heartbeat = nullptr);
// Reads COLMAP's feature_extractor log into summary->no_exif / default_focal_px / focal_priors /
// unreadable / other_size: COLMAP prints "Focal Length: <f>px (Prior)" for a focal from EXIF, no
// "(Prior)" for its default guess, "ERROR: Failed to read image" for a file it cannot decode and
// "ERROR: Single camera specified, but images have different dimensions" for a photo of another
// size than the first when one camera is shared. The lists sorted by name.
void ParseFeatureExtractionLog(const std::string& log_path, SfmSummary* summary);
// Groups of files in `dir` among `names` with the same bytes (each group sorted, groups in name
// order); only files of equal size are read (SHA-256).
std::vector<std::vector<std::string>> IdenticalFiles(const std::string& dir, const std::vector<std::string>& names);
// Runs one stage with its output in log_path (replaced), reporting progress (the fraction from
// the log's counters; `images`, when known, for the mapper's); returns its seconds. A failure
// throws InputError naming the log, the exit code (or signal) and the log's last lines.
double RunSfmStage(const SfmStage& stage, const std::string& log_path, int index, int count,
                   const SfmProgress& progress, size_t images = 0);
// How far a COLMAP stage is, from its log's text: the last "[i/N]" (extraction, undistortion) or
// "Registering image #k (n)" (the mapper: n of `images`), whichever comes later; -1 when none.
double FractionInLog(const std::string& text, size_t images);
// The last `lines` non-empty lines of a text file, glog stack-trace frames ("    @ 0x...") left
// out ("" when unreadable).
std::string TailOfFile(const std::string& path, int lines);

}  // namespace candi::photogrammetry
