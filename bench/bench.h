// candi's benchmarks as a library (candi_bench; the relief one in candi_bench_relief, which links
// libtorch): each prints a table on stdout, accuracy against time or throughput, and returns 0
// (the scale benchmark returns 2 when one of its runs failed).
// `candi bench ...` (apps/bench.cc) runs them; so do the programs in bench/ that need no
// command line. docs/benchmarks.md keeps their current tables.
// Failures: std::invalid_argument for invalid options, InputError for unreadable data.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace candi::bench {

// `candi bench render|foundation|dense`.
struct BenchOptions {
  std::string what = "render";        // render | foundation | dense
  uint64_t points = 1000000;          // render: points in the generated scene
  int width = 256, height = 256;      // render: image; dense: the larger synthetic set's images
  int threads = 1;                    // [0, 256], 0 = all
  std::string data;                   // dense: ../shared/data -> the Sceaux comparison with OpenMVS
  double scale = 0.5;                 // dense --data: PatchMatch resolution scale, [0.05, 1]
  int iterations = 3;                 // dense --data, --campaign: PatchMatch rounds, [1, 50]
  // dense --campaign: the streaming run (a child `candi dense`) on generated campaigns of these
  // photo counts (e.g. "50,100,200,400") at `campaign_size` px; "" none.
  std::string campaign;
  int campaign_size = 800;            // [64, 8192]
  int views = 4;                      // dense --campaign: source views
  int grid_at = 0;                    // dense --campaign: scale x rounds x views table at this count
  uint64_t max_memory_mb = 0;         // dense --campaign: candi dense --max-memory (0: its default)
  std::string work_dir = "candi-bench-dense";
  bool keep = false;                  // keep the campaigns' workspaces
  void Check() const;
};
int RunBench(const BenchOptions& options);
// candi dense on generated campaigns: seconds a photo, peak memory, points, accuracy and
// completeness at 1, 2 and 5 cm against the true surface; the fitted law; the accuracy grid.
int RunDenseCampaign(const BenchOptions& options);
// SPBR accuracy against time: RMSE against depth-sorted blending for L = 1 ... 1024.
int RunRenderAccuracy(const BenchOptions& options);
// Foundation from sections: accuracy against time of N and M, and the paper-scale run.
int RunFoundationAccuracy();
// PatchMatch on the synthetic scene: completeness and accuracy against resolution and rounds.
int RunDenseAccuracy(const BenchOptions& options);
// PatchMatch on the shared data's Sceaux photos against its OpenMVS cloud.
int RunDenseSceaux(const BenchOptions& options);

// `candi bench scale`: pack and render 10^7, 10^8 (10^9) generated points, one process and
// `mpirun -np K` (child processes of this executable: each one's time and peak memory its own).
struct ScaleBenchOptions {
  std::string sizes = "1e7,1e8";       // point counts
  bool billion = false;                // add 1e9 (~8 GB archive, ~28 GB temporary, minutes)
  std::string work_dir = "candi-bench-scale";  // generated data (deleted afterwards)
  std::string size = "1024x1024";      // image WxH
  int repeat_level = 100;
  int ranks = 2;                       // mpirun -np; 0 skips the MPI runs, [0, 64]
  bool keep = false;                   // keep the generated data
  void Check() const;
};
int RunScaleBench(const ScaleBenchOptions& options);

// `candi bench view`: the viewer's frame latency, frame rate and convergence.
struct ViewBenchOptions {
  std::string sizes = "1e7";
  bool billion = false;
  std::string work_dir = "candi-bench-view";
  std::string size = "1024x768";       // image WxH
  int repeat_level = 100;
  int threads = 0;                     // [0, 256]
  int orbit_frames = 60;
  int runs = 3;                        // convergence runs (the median is printed), [1, 100]
  bool keep = false;                   // keep the archives, and reuse kept ones
  void Check() const;
};
int RunViewBench(const ViewBenchOptions& options);

// `candi bench section`: section accuracy against slab thickness, and time at scale.
struct SectionBenchOptions {
  std::string sizes = "1e7";
  bool billion = false;
  std::string work_dir = "candi-bench-view";  // shared with bench view: keep reuses its archives
  std::string drawing = "examples/borobudur/foundation.dxf";  // the accuracy table ("" skips it)
  double thickness = 0.1;              // m, > 0
  int threads = 0;                     // [0, 256]
  bool keep = false;
  void Check() const;
};
int RunSectionBench(const SectionBenchOptions& options);

// `candi bench publish`: candi publish on generated archives: seconds and points/s on 1 and 2
// threads, bytes a point, bytes before the first image, points an ensemble
// draws (what a GPU's GL_POINTS rate turns into a frame time). The browser's side (time to the
// first image and to convergence, throttled and not; the longest main-thread task) is
// bench/publish_browser_bench.py.
struct PublishBenchOptions {
  std::string sizes = "1e7";
  bool billion = false;
  std::string work_dir = "candi-bench-view";  // shared with bench view and section: keep reuses
  int repeat_level = 100;              // L of the pages, [1, 1000]
  std::string threads = "1,2";         // thread counts, each [1, 256]
  int runs = 3;                        // the median of runs is printed, [1, 100]
  bool keep = false;                   // keep the archives and the last site
  void Check() const;
};
int RunPublishBench(const PublishBenchOptions& options);

// `candi bench compare`: the deviation methods on a case with known change (a wavy surface with
// 2 mm noise on both sides, moved 5 mm along its normal inside a disc): per setting (C2C plain or
// with a local model, M3C2 at several D and d, the reference thinned) the seconds on 1 and 2
// threads and the error against the truth; then C2C beside CloudCompare's on the same files
// (when it is installed), both timed end to end and in their distance step.
struct CompareBenchOptions {
  double points = 1e6;                 // points in each cloud, [1e3, 1e9]
  std::string threads = "1,2";         // thread counts, each [1, 256]
  int runs = 3;                        // the median of runs is printed, [1, 100]
  std::string methods = "c2c,m3c2";    // which rows: c2c, m3c2 or both
  bool quick = false;                  // only the first row of each method
  bool cloudcompare = true;            // also time CloudCompare (skipped when not installed)
  std::string work_dir = "candi-bench-compare";
  uint64_t seed = 1;
  void Check() const;
};
int RunCompareBench(const CompareBenchOptions& options);

// `candi bench campaign`: candi sfm on generated campaigns (scenes/campaign.h) of N photos: seconds
// a stage, pairs matched and verified, photos registered, camera centres against the truth after
// one similarity, peak memory (candi's, COLMAP's children's); the fitted law seconds = a N^b; at
// `recall_at` photos the chosen pairs' recall of those exhaustive matching verifies, and with
// `colmap_side` COLMAP's vocab_tree_builder + vocab_tree_matcher on the same features.
struct CampaignBenchOptions {
  std::string sizes = "50,100,200,400";  // photo counts, each [8, 5000]
  int size = 800;                      // the photos' long side, pixels, [64, 8192]
  int chunks = 3;                      // sessions, [1, 64]
  int threads = -1;                    // extraction and matching threads, -1 = all
  int recall_at = 200;                 // 0: no recall row
  bool colmap_side = true;             // COLMAP's vocabulary-tree matcher beside, at recall_at
  std::string work_dir = "candi-bench-campaign";
  bool keep = false;                   // keep the campaigns and workspaces
  uint64_t seed = 1;
  void Check() const;
};
int RunCampaignBench(const CampaignBenchOptions& options);
// seconds = a N^b fitted in logs (least squares): {a, b}. At least two distinct N.
std::pair<double, double> FitPowerLaw(const std::vector<double>& n, const std::vector<double>& seconds);

// `candi bench relief` (candi_bench_relief): network width x training time -> accuracy, training
// and prediction seconds; or, on real photos, fine-tuning seconds -> accuracy.
struct ReliefBenchOptions {
  std::string widths = "32,64,128";    // decoder widths (growth = width / 8)
  double seconds = 60;                 // training budget per width
  int train_panels = 12, eval_panels = 3;
  uint64_t seed = 1;
  int threads = 1;                     // libtorch threads, [1, 256]
  std::string pairs;                   // real photos, held-out photos: a `relief dataset --colmap` folder
  std::vector<std::string> parts;      // real photos, held-out surfaces: one folder per part (--holdout-region)
  bool relative = false;               // fine-tune into a relative model
  std::string model = "examples/relief/relief_model.pt";
  std::string finetune_seconds = "60,240";
  double edge_weight = 1;              // [0, 1000]
  double learning_rate = 3e-4;
  void Check() const;
};
int RunReliefBench(const ReliefBenchOptions& options);

}  // namespace candi::bench
