// The `candi` subcommands: plain argument structs (filled by cli.cc, the only CLI11 unit) and
// their entry points. Each Run* returns the process exit code (see ExitCode) and throws
// InputError for bad input, std::invalid_argument for bad option values.
#pragma once

#include <string>
#include <vector>

#include "core/clip.h"
#include "section/section_path.h"

namespace candi::app {

enum ExitCode : int { kOk = 0, kUsage = 1, kBadInput = 2, kInternal = 3 };

struct GlobalArgs {
  int verbosity = 0;  // -v: debug logging; -q: warnings only (-1)
};

struct InfoArgs {
  std::string input;
  std::string columns;   // XYZ/PTS column spec
  bool json = false;     // machine-readable output
  bool no_scan = false;  // header only: skip the pass over the points
};
int RunInfo(const InfoArgs& args);

struct ConvertArgs {
  std::string input, output;
  std::string shift;        // "" (keep the input's), "auto", "none" or "x,y,z"
  std::string columns;      // input XYZ/PTS column spec
  std::string out_columns;  // output XYZ/PTS column spec
  std::string ply_encoding = "binary";  // binary | binary_be | ascii
  std::string precision = "auto";       // auto | float | double
  std::string las_scale;                // "s" or "sx,sy,sz"
  int las_format = -1;
  int las_version = -1;                 // minor version: 2, 3, 4
  std::string crs;                      // the input's CRS when the file states none
  std::string to_crs;                   // reproject into this CRS with PROJ
};
int RunConvert(const ConvertArgs& args);

struct DemoArgs {
  std::string output_dir = "demo_out";
  int width = 1024, height = 768;
  unsigned long long seed = 1;
  bool quick = false;                 // the reduced scene CI runs (fewer points, L = 32)
  bool full = false;                  // paper scale: every panel through the network at the
                                      // model's resolution (default: hidden panels at the photo's)
};
int RunDemo(const DemoArgs& args);

struct OpacityArgs {
  std::string input, output;
  double alpha = -1;            // target opacity [0, 1] (required)
  int repeat_level = 0;         // L >= 1 (required)
  int image_size = 0;           // pixels across the largest extent; exactly one of this and
  double pixel_size = 0;        // the pixel footprint's side in metres
  unsigned long long seed = 1;
  int neighbours = 32;          // target neighbours for the automatic density radius
  double radius = 0;            // density radius in metres; 0 = automatic
  std::string method = "kdtree";  // kdtree | voxel
  int threads = 0;              // 0 = all available
};
int RunOpacity(const OpacityArgs& args);

// --clip-box and --clip-plane (apps/arg_parse.h ParseClip).
struct ClipArgs {
  std::string box;
  std::vector<std::string> planes;
};

struct RenderArgs {
  std::vector<std::string> inputs;
  std::string output;                 // 8-bit PNG
  std::string output16;               // optional 16-bit PNG (analysis)
  int repeat_level = 100;             // L
  unsigned long long seed = 1;
  std::string size = "1024x768";      // WxH (overrides a view's size when given explicitly)
  bool size_given = false;
  std::string view, save_view;        // JSON views (world coordinates)
  std::string background = "0,0,0";  // r,g,b
  std::string brightness = "auto";    // auto | none | a gain >= 0
  std::vector<double> alpha;          // per input (or one for all): opacity control
  bool opaque = false;                // L = 1, multiplicities ignored
  int threads = 0;
  double point_size = 1.0;
  int preview = 0;                    // > 0: only the first k ensembles
  std::string mode = "auto";          // auto | memory | stream
  double memory_mb = 2048;            // stream mode and archives: z-buffers resident per pass
  double chunk_budget_mb = 256;       // archive input: chunks mapped at once (8 bytes a point)
  std::string columns;                // XYZ/PTS inputs
  std::string up, from;               // default view: world up (x,y,z), viewing direction
  std::string cameras;                // default view: oriented by a COLMAP model's cameras
  ClipArgs clip;                      // only points inside are drawn
};
int RunRender(const RenderArgs& args);

// candi section (cmd_section.cc): a slab's points as an image and section lines.
struct SectionArgs {
  std::vector<std::string> inputs;    // an archive, a build directory, or point files
  std::string output;                 // a directory: section.png .dxf .csv .svg .json
  std::string plane;                  // px,py,pz,nx,ny,nz
  std::string through;                // x1,y1[,z1],x2,y2[,z2]: the vertical plane through two points
  std::string path;                   // x1,y1,x2,y2,...: an unrolled section along a plan polyline
  double thickness = 0;               // m, > 0
  double spacing = 0, max_gap = 0;    // section lines (0: automatic)
  int width = 1600;                   // image pixels across (with --pixel 0)
  double pixel = 0;                   // m per pixel (0: from --width)
  int repeat_level = 10;              // L of the image (a slab is thin: few ensembles blend it)
  unsigned long long seed = 1;
  double point_size = 2.0;
  double opacity = 0.7;               // of a pixel one slab point covers (its copies: opacity x L)
  std::string colours = "layer";      // layer | data
  std::string background = "255,255,255";
  std::vector<std::string> layers;    // only these layers (empty: all)
  std::string columns;
  int threads = 0;
  ClipArgs clip;
};
int RunSection(const SectionArgs& args);
// The outputs of `candi section` for a given slab and clipping (world) into args.output; returns
// the summary (section.json's text). `print`: the table on stdout.
std::string RunSectionInto(const SectionArgs& args, const section::SectionPath& section, const ClipRegion& clip, bool print);

// candi view (cmd_view.cc): the browser viewer (view/).
struct ViewArgs {
  std::vector<std::string> inputs;    // a build directory, an archive, or point files
  std::string host = "127.0.0.1";
  int port = 8765;                    // 0: any free port
  std::string up;                     // x,y,z world up (default z; COLMAP's frame: 0,-1,0)
  std::string from;                   // x,y,z direction from the eye to the target
  std::string cameras;                // a COLMAP model: up and viewing side from its cameras
  std::string columns;                // XYZ/PTS inputs
  int threads = 0;
  ClipArgs clip;                      // the clipping the page starts with
};
int RunView(const ViewArgs& args);

// candi bench view (cmd_bench_view.cc): the viewer's frame latency, frame rate and convergence.
struct BenchViewArgs {
  std::string sizes = "1e7";
  bool billion = false;
  std::string work_dir = "candi-bench-view";
  std::string size = "1024x768";
  int repeat_level = 100;
  int threads = 0;
  int orbit_frames = 60;
  int runs = 3;
  bool keep = false;                  // keep the archives, and reuse kept ones (pack s 0)
};
int RunBenchView(const BenchViewArgs& args);

// candi bench section (cmd_bench_section.cc): section accuracy vs thickness, and time at scale.
struct BenchSectionArgs {
  std::string sizes = "1e7";
  bool billion = false;
  std::string work_dir = "candi-bench-view";  // shared with bench view: --keep reuses its archives
  std::string drawing = "examples/borobudur/foundation.dxf";  // the accuracy table ("" skips it)
  double thickness = 0.1;
  int threads = 0;
  bool keep = false;
};
int RunBenchSection(const BenchSectionArgs& args);

struct BenchArgs {
  std::string what = "render";        // render
  unsigned long long points = 1000000;
  int width = 256, height = 256;
  int threads = 1;
  std::string data;                   // dense: ../shared/data -> the Sceaux comparison with OpenMVS
  double scale = 0.5;                 // dense --data: PatchMatch resolution scale
  int iterations = 3;                 // dense --data: PatchMatch rounds
};
int RunBench(const BenchArgs& args);
int RunBenchFoundation();  // `candi bench foundation`: accuracy vs time of N and M, paper scale

// candi relief synth|dataset|train|predict|points|eval (cmd_relief*.cc): the buried-relief path.
struct ReliefSynthArgs {
  std::string output_dir;
  int count = 8;                      // panels
  int width = 800;                    // pixels along the panel
  unsigned long long seed = 1;
  double width_m = 2.7, height_m = 0.92, depth_m = 0.15;
  bool no_shadows = false, no_stains = false, no_blur = false, no_grain = false;
  bool no_tone = false, no_fading = false;
};
int RunReliefSynth(const ReliefSynthArgs& args);
// True in the executable that holds the relief path (candi-relief): the Run Relief* functions above
// run in this process. Elsewhere they are stubs, and callers (candi build) start candi-relief.
bool ReliefInProcess();

struct ReliefDatasetArgs {
  std::vector<std::string> inputs;    // scans (point files) or synthetic panels (*_photo.png, folders)
  std::string output_dir;
  double pixels_per_m = 800 / 2.7;
  int patch = 128, stride = 64;
  double val_fraction = 0.1;          // inputs (or patches, with one input) held out for validation
  std::string frame = "auto";         // scans: auto | panel
  double depth_m = 0.15;
  double panel_width_m = 2.7;         // width of a photo input without a recorded resolution
  bool no_relight = false;            // scans: use the scan's grey instead of a raking-light photo
  unsigned long long seed = 1;
  // Real photographs: pairs (photo, depth in its camera, mask) from a COLMAP model + its photos,
  // the inputs being the dense cloud(s) in the model's frame.
  std::string colmap, images;          // sparse model folder, photo folder
  std::vector<std::string> holdout;    // image names (or stems) kept out of training -> holdout/
  int max_side = 512;                  // pair size: longer side, pixels
};
int RunReliefDataset(const ReliefDatasetArgs& args);
// The real-photo mode of RunReliefDataset (cmd_relief_photos.cc; candi-relief only).
int RunReliefPhotoDataset(const ReliefDatasetArgs& args);

struct ReliefTrainArgs {
  std::string data_dir, output;
  int epochs = 10, batch = 8;
  int growth = 12, decoder_width = 128;
  std::string blocks = "4,6,8,6";
  double learning_rate = 1e-3, end_learning_rate = 1e-4;
  double max_seconds = 0;
  std::string checkpoint;             // default: <output>.ckpt
  bool resume = false;
  std::string finetune;               // start from this model's weights (fresh optimiser)
  double edge_weight = 0;             // weight of the edge loss term (0 = off)
  unsigned long long seed = 1;
  int threads = 1;
};
int RunReliefTrain(const ReliefTrainArgs& args);

struct ReliefPredictArgs {
  std::string photo, model, output;
  std::string output16;               // optional 16-bit depth (levels * 256)
  double width_m = 2.7;               // the photo's panel width (sets its resolution); 0 = model's
  int tile = 128, overlap = 32;
  int threads = 1;
};
int RunReliefPredict(const ReliefPredictArgs& args);

struct ReliefPointsArgs {
  std::string photo, depth, output;
  double width_m = 2.7, height_m = 0.92, depth_m = 0.15;
};
int RunReliefPoints(const ReliefPointsArgs& args);

struct ReliefEvalArgs {
  std::vector<std::string> models;    // optional: baselines only without one
  int panels = 4, width = 800;
  unsigned long long seed = 1000;     // held-out series (training uses other seeds)
  std::string photo, depth;           // or: one photo and its ground-truth depth
  std::string pairs;                  // or: a folder of photo pairs (relief_photo_pairs.h)
  double level_per_pixel = 0;         // normals (0: from the panel geometry; 1 for pairs)
  int normal_step = 0;                // normals: difference step, pixels (0: 1, 4 for pairs)
  double edge_jump = 10;              // edges: levels
  int edge_tolerance = 2;             // edges: pixels
  double light_azimuth = -1, light_elevation = -1;  // for SFS on a photo (default: its PNG text)
  double width_m = 2.7;
  int tile = 128, overlap = 32;
  int threads = 1;
};
int RunReliefEval(const ReliefEvalArgs& args);

struct BenchReliefArgs {
  std::string widths = "32,64,128";   // decoder widths (growth = width / 8 ... see cmd_bench_relief)
  double seconds = 60;                // training budget per width
  int train_panels = 12, eval_panels = 3;
  unsigned long long seed = 1;
  int threads = 1;
  std::string pairs;                  // real photos: a `relief dataset --colmap` folder
  std::string model = "examples/relief/relief_model.pt";
  std::string finetune_seconds = "60,240";
  double edge_weight = 1;
  double learning_rate = 3e-4;
};
int RunBenchRelief(const BenchReliefArgs& args);

struct FoundationArgs {
  std::string input;                 // the section drawing (ASCII DXF)
  std::string output;                // point file (.ply .las .xyz .pts); merged unless split
  std::vector<std::string> layers;   // layers to build; empty = every layer holding a section
  int samples_per_side = 1000;       // N, Hermite samples per side
  int angular_steps = 90;            // M, steps per half-turn
  unsigned long long count = 0;      // total points over the layers (split by area); or
  double density = 0;                // points per m^2 (default 50 when neither is given)
  int per_triangle = 0;              // > 0: the paper's fixed count per triangle instead
  std::string mode = "auto";         // auto | blend | sweep
  std::string mesh;                  // optional mesh output (.obj .off .ply); per layer if several
  bool split = false;                // one point file per layer, <stem>_<layer><ext>
  bool close_base = false;           // close each mesh's bottom ring
  bool no_check = false;             // skip the CGAL checks
  bool no_self_intersection = false; // skip CGAL's self-intersection test only
  std::string axis_x;                // drawing x of the axis, m; "" = through the reference point
  double symmetry_tolerance = 1e-3;  // relative to the section's extent
  double chord_tolerance = 0.005;    // bulge arcs, m
  double join_tolerance = 1e-6;      // LINE chains, m
  unsigned long long seed = 1;
  int threads = 0;
};
int RunFoundation(const FoundationArgs& args);

// candi sfm IMAGES -o WORKSPACE (cmd_sfm.cc): COLMAP structure from motion into a dense workspace.
struct SfmArgs {
  std::string images, workspace;
  std::string colmap;                // executable; "" = $CANDI_COLMAP, else `colmap` on PATH
  int max_image_size = 1600;         // pixels (SIFT and the undistorted dense images)
  int max_features = 4096;           // SIFT features per image
  int exhaustive_max_images = 50;    // more images: sequential matching
  std::string camera_model = "SIMPLE_RADIAL";
  bool camera_per_image = false;     // default: one camera shared by all photos
  int threads = -1;                  // -1 = all
  bool overwrite = false;
};
int RunSfm(const SfmArgs& args);
struct DenseArgs {
  std::string workspace;              // COLMAP dense workspace: images/ + sparse/ (PINHOLE cameras)
  std::string output;                 // fused points (.ply .las .xyz .pts)
  double resolution_scale = 1.0;      // images resampled by this factor, (0, 1]
  int iterations = 3;                 // PatchMatch red-black rounds
  int window = 4;                     // window radius, pixels
  int views = 4;                      // source views per reference
  int min_consistent = 2;             // geometric consistency: agreeing source views
  int min_views = 3;                  // fusion: views per point
  bool no_maps = false;               // do not write WORKSPACE/stereo/*_maps
  unsigned long long seed = 1;
  int threads = 0;
};
int RunDense(const DenseArgs& args);
int RunBenchDense(const BenchArgs& args);  // `candi bench dense`
int RunBenchDenseSceaux(const BenchArgs& args);  // `candi bench dense --data DIR` (cmd_bench_sceaux.cc)
// candi register / candi clean (cmd_register.cc, cmd_clean.cc): ICP and cleaning with PCL.
struct RegisterArgs {
  std::string moving, fixed, output;
  double max_distance = 0.5;     // m: correspondences farther apart are ignored
  int iterations = 50;
  std::string method = "plane";  // point | plane
  double voxel = 0;              // m: thin both clouds for the solve; 0 = off
  std::string transform_out;     // optional JSON: the 4x4 and the figures
  std::string initial;           // optional JSON: initial fixed_from_moving (same format)
};
int RunRegister(const RegisterArgs& args);

struct CleanArgs {
  std::string input, output;
  int sor_k = 16;                // statistical outlier removal: neighbours
  double sor_std = 3.0;          // ... threshold in standard deviations
  bool no_sor = false;
  double voxel = 0;              // m: keep one point per voxel; 0 = off
};
int RunClean(const CleanArgs& args);
// candi pack IN... -o ARCHIVE (cmd_pack.cc): the compact chunked render archive (render/archive.h).
struct PackArgs {
  std::vector<std::string> inputs;
  std::string output;                  // archive directory
  unsigned long long chunk_points = 65536;
  double memory_mb = 400;              // sort buffers (~100 bytes a point)
  std::string columns;                 // XYZ/PTS inputs
  int threads = 0;
};
int RunPack(const PackArgs& args);

// candi bench scale (cmd_bench_scale.cc): pack and render 10^7, 10^8 (10^9) generated points,
// one process and mpirun -np 2.
struct BenchScaleArgs {
  std::string sizes = "1e7,1e8";       // point counts
  bool billion = false;                // add 1e9 (~8 GB archive, ~28 GB temporary, minutes)
  std::string work_dir = "candi-bench-scale";  // generated data (deleted afterwards)
  std::string size = "1024x1024";
  int repeat_level = 100;
  int ranks = 2;                       // mpirun -np; 0 skips the MPI runs
  bool keep = false;                   // keep the generated data
};
int RunBenchScale(const BenchScaleArgs& args);
// candi georef (cmd_georef.cc): total-station targets -> robust similarity -> georeferenced output.
struct GeorefArgs {
  std::string input;                 // point file, or a COLMAP sparse model folder
  std::string targets;               // targets CSV (reconstruction/photogrammetry/georef.h)
  std::string output;                // point file (IN a point file) or folder (IN a model)
  std::string model;                 // COLMAP sparse model of the picks (default: IN if a model)
  std::string picks;                 // picks CSV name,image,u,v
  std::string loss = "huber";        // none | huber | cauchy
  double loss_scale = 0.05;          // m
  double outlier_threshold = 0;      // m; 0 = robust (k * max(MAD sigma, accuracy))
  bool rigid = false;                // scale fixed to 1
  std::string crs;                   // the CRS of the survey coordinates (stated in OUT)
  std::string targets_crs;           // the targets' CRS; transformed into `crs` with PROJ
};
int RunGeoref(const GeorefArgs& args);

// candi colorcorrect (cmd_colorcorrect.cc): a colour card's 3x4 matrix applied to an image or points.
struct ColorCorrectArgs {
  std::string input, output;         // PNG image or point file with colours
  std::string patches;               // CSV of measured vs reference patch colours, or
  std::string card, corners;         // the card photo (PNG) and its patches' corners CSV
  double outlier_delta_e = 10;       // CIEDE2000
  int max_outliers = 2;
};
int RunColorCorrect(const ColorCorrectArgs& args);

// candi build SCENE -o ARCHIVE (cmd_build.cc, scene.h): the integrated archive of every layer.
struct BuildArgs {
  std::string scene;                 // scene JSON (apps/scene.h)
  std::string output;                // archive folder (created; its parent must exist)
  int threads = 0;
  bool resume = false;               // reuse the stages an earlier (interrupted) build finished
};
int RunBuild(const BuildArgs& args);

// candi relief place (cmd_relief_place.cc): panels placed on the wall by a robust fit of their
// corners / edge points to documented positions (reconstruction/relief/relief_place.h).
struct ReliefPlaceArgs {
  std::string correspondences, output;  // CSV panel,point,x,y,z,E,N,H[,accuracy]; placements JSON
  std::vector<std::string> panels;      // the panels' point files (<panel>.ply) or folders of them
  std::string points_out;               // folder for the panels in world coordinates
  bool sim3 = false;                    // estimate the scale too (default: rigid)
  std::string loss = "huber";
  double loss_scale = 0.01;             // m
  double accuracy = 0.005;              // m, for rows without an accuracy
  double tolerance_mm = 20;             // RMS above this: the panel does not fit
};
int RunReliefPlace(const ReliefPlaceArgs& args);

}  // namespace candi::app
