// candi bench render|foundation|dense, bench scale, view, section, publish, compare and relief: the
// benchmarks of bench/ (bench/bench.h). `bench relief` runs in candi-relief (relief_network.cc).
#include <string>

#include "apps/commands.h"
#include "bench/bench.h"

namespace candi::apps {

namespace {

// --sizes, --billion and --work-dir of bench view, section and publish: the generated archives
// (the same field names in their options).
template <typename Options>
void AddGeneratedArchives(Command& c, Options& o, const std::string& work_dir_help) {
  c.Option("--sizes", o.sizes, "Point counts, comma separated (e.g. 1e7,1e8)");
  c.Flag("--billion", o.billion, "Also 1e9 points (~8 GB archive on disk)");
  c.Option("--work-dir", o.work_dir, work_dir_help);
}

void AddBenchCommand(Command& root) {
  bench::BenchOptions& a = root.Keep<bench::BenchOptions>();
  Command c = root.Add("bench", "Benchmarks: `candi bench render` prints SPBR accuracy vs time for L = 1 ... 1024");
  c.Option("what", a.what, "What to measure: render (SPBR), foundation (sections to points), dense (PatchMatch on "
           "the synthetic scene)").OneOf({"render", "foundation", "dense"});
  c.Option("--points", a.points, "Points in the generated scene");
  c.Option("--width", a.width, "Image width").Range(16, 8192);
  c.Option("--height", a.height, "Image height").Range(16, 8192);
  c.Option("--threads", a.threads, "Threads (0: all)").Range(0, 256);
  c.Option("--data", a.data, "dense: the shared data folder; runs candi dense on its Sceaux photos against its "
           "OpenMVS cloud instead of the synthetic table");
  c.Option("--scale", a.scale, "dense --data, --campaign: resolution scale").Range(0.05, 1.0);
  c.Option("--iterations", a.iterations, "dense --data, --campaign: PatchMatch rounds").Range(1, 50);
  c.Option("--campaign", a.campaign, "dense: photo counts, comma separated; candi dense (streamed) on generated "
           "campaigns, scored against the true surface at 1, 2 and 5 cm");
  c.Option("--campaign-size", a.campaign_size, "dense --campaign: the photos' long side, pixels").Range(64, 8192);
  c.Option("--views", a.views, "dense --campaign: source views").Range(1, 32);
  c.Option("--grid-at", a.grid_at, "dense --campaign: at this photo count, the table of resolution scale x rounds x "
           "source views (0: none)");
  c.Option("--max-memory", a.max_memory_mb, "dense --campaign: candi dense --max-memory, MB (0: its default)");
  c.Option("--work-dir", a.work_dir, "dense --campaign: folder for the workspaces (deleted afterwards)");
  c.Flag("--keep", a.keep, "dense --campaign: keep the workspaces");
  c.Run([&a] { return bench::RunBench(a); });
  c.Footer("Examples: candi bench render --points 1000000; candi bench dense --data ../shared/data --threads 2\n"
           "          candi bench dense --campaign 50,100,200,400 --campaign-size 800 --threads 2");
}

void AddScaleBench(Command& bench) {
  bench::ScaleBenchOptions& a = bench.Keep<bench::ScaleBenchOptions>();
  Command c = bench.Add("scale", "Pack and render generated scenes of 1e7, 1e8 (1e9) points: points/s, s/frame, "
                                 "peak RSS");
  c.Option("--sizes", a.sizes, "Point counts, comma separated");
  c.Flag("--billion", a.billion, "Also 1e9 points (~8 GB archive, ~28 GB temporary disk, minutes)");
  c.Option("--work-dir", a.work_dir, "Folder for the generated data (deleted afterwards)");
  c.Option("--size", a.size, "Image size WxH");
  c.Option("-L,--repeat-level", a.repeat_level, "Ensembles");
  c.Option("--ranks", a.ranks, "mpirun -np for the MPI runs (0: none)").Range(0, 64);
  c.Flag("--keep", a.keep, "Keep the generated data");
  c.Run([&a] { return bench::RunScaleBench(a); });
  c.Footer("Example: candi bench scale --sizes 1e7");
}

void AddViewBench(Command& bench) {
  bench::ViewBenchOptions& a = bench.Keep<bench::ViewBenchOptions>();
  Command c = bench.Add("view", "The viewer's renderer on generated archives: first-frame latency (p50/p95) and "
                                "frames/s during an orbit, seconds to the converged image, peak memory");
  AddGeneratedArchives(c, a, "Folder for the generated archive (deleted afterwards)");
  c.Option("--size", a.size, "Image size WxH");
  c.Option("-L,--repeat-level", a.repeat_level, "Ensembles of the converged image");
  c.Option("--threads", a.threads, "Render threads (0: all)").Range(0, 256);
  c.Option("--orbit-frames", a.orbit_frames, "Camera changes in the orbit");
  c.Option("--runs", a.runs, "Convergence runs (the median is printed)").Range(1, 100);
  c.Flag("--keep", a.keep, "Keep the generated archives, and reuse those an earlier --keep run kept");
  c.Run([&a] { return bench::RunViewBench(a); });
  c.Footer("Example: candi bench view --sizes 1e7,1e8 --threads 2");
}

void AddSectionBench(Command& bench) {
  bench::SectionBenchOptions& a = bench.Keep<bench::SectionBenchOptions>();
  Command c = bench.Add("section", "Sections: accuracy vs slab thickness on the bundled foundation, and seconds and "
                                   "chunks read on generated archives");
  AddGeneratedArchives(c, a, "Folder for the generated data (shared with bench view)");
  c.Option("--drawing", a.drawing, "The drawing of the accuracy table (\"\" skips it)");
  c.Option("--thickness", a.thickness, "Slab thickness of the scale table, m");
  c.Option("--threads", a.threads, "Threads (0: all)").Range(0, 256);
  c.Flag("--keep", a.keep, "Keep the generated archives, and reuse those an earlier --keep run kept");
  c.Run([&a] { return bench::RunSectionBench(a); });
  c.Footer("Example: candi bench section --sizes 1e7,1e8 --keep");
}

void AddPublishBench(Command& bench) {
  bench::PublishBenchOptions& a = bench.Keep<bench::PublishBenchOptions>();
  Command c = bench.Add("publish", "candi publish on generated archives: points/s by threads, bytes a point, bytes "
                                   "before the first image, points an ensemble draws");
  AddGeneratedArchives(c, a, "Folder for the generated data (shared with bench view and section)");
  c.Option("-L,--repeat-level", a.repeat_level, "L of the site's pages");
  c.Option("--threads", a.threads, "Thread counts, comma separated");
  c.Option("--runs", a.runs, "Runs of each setting (the median is printed)");
  c.Flag("--keep", a.keep, "Keep the generated archives and sites, and reuse archives an earlier --keep run kept");
  c.Run([&a] { return bench::RunPublishBench(a); });
  c.Footer("Example: candi bench publish --sizes 1e7,1e8 --keep   (then bench/publish_browser_bench.py for the "
           "browser's side)");
}

void AddCompareBench(Command& bench) {
  bench::CompareBenchOptions& a = bench.Keep<bench::CompareBenchOptions>();
  Command c = bench.Add("compare", "candi compare on a known change: seconds and error against the truth per "
                                   "setting (C2C models, M3C2 scales, thinning), and C2C beside CloudCompare's");
  c.Option("--points", a.points, "Points in each cloud").Range(1e3, 1e9);
  c.Option("--threads", a.threads, "Thread counts, comma separated");
  c.Option("--runs", a.runs, "Runs of each setting (the median is printed)");
  c.Option("--methods", a.methods, "Rows: c2c, m3c2 or c2c,m3c2");
  c.Flag("--quick", a.quick, "Only the first row of each method (C2C nearest point, M3C2 at its smallest scales)");
  c.FlagOff("--no-cloudcompare", a.cloudcompare, "Do not time CloudCompare");
  c.Option("--work-dir", a.work_dir, "Folder for the generated clouds");
  c.Option("--seed", a.seed, "Seed of the generated clouds");
  c.Run([&a] { return bench::RunCompareBench(a); });
  c.Footer("Example: candi bench compare --points 1e7 --runs 3");
}

void AddReliefBench(Command& bench) {
  bench::ReliefBenchOptions& a = bench.Keep<bench::ReliefBenchOptions>();
  Command c = bench.Add("relief", "Relief depth: network width x training time -> accuracy, training and prediction "
                                  "seconds, 3200x1024 photo -> points");
  c.Option("--widths", a.widths, "Decoder widths to train, e.g. 32,64,128");
  c.Option("--seconds", a.seconds, "Training budget per width, s");
  c.Option("--train-panels", a.train_panels, "Synthetic training panels").Range(1, 10000);
  c.Option("--eval-panels", a.eval_panels, "Held-out panels").Range(1, 10000);
  c.Option("--seed", a.seed, "Seed of the training series");
  c.Option("--threads", a.threads, "libtorch threads").Range(1, 256);
  c.Option("--pairs", a.pairs, "Real photos instead, held-out photos: a `relief dataset --colmap --holdout` folder; the "
           "model is fine-tuned on train/ for each budget and scored on holdout/");
  c.Option("--parts", a.parts, "Real photos, unseen surfaces: a `relief dataset --holdout-region` folder per held-out "
           "part (repeatable); each part is fine-tuned on its train/ and scored on its holdout/, then the mean");
  c.Option("--model", a.model, "Real photos: the model to fine-tune");
  c.Flag("--relative", a.relative, "Real photos: fine-tune into a relative model (scale-and-shift-invariant loss)");
  c.Option("--finetune-seconds", a.finetune_seconds, "Real photos: fine-tuning budgets, s");
  c.Option("--edge-loss", a.edge_weight, "Weight of the edge term in the edge-guided rows (0: plain rows only)")
      .Range(0.0, 1000.0);
  c.Option("--lr", a.learning_rate, "Real photos: fine-tuning learning rate");
  c.Run([&a] { return RunBenchRelief(a); });
  c.Footer("Examples: candi bench relief --widths 32,64 --seconds 60\n"
           "          candi bench relief --pairs pairs --model examples/relief/relief_model.pt "
           "--finetune-seconds 60,240\n"
           "          candi bench relief --parts left --parts centre --parts right --finetune-seconds 180");
}

void AddCampaignBench(Command& bench) {
  bench::CampaignBenchOptions& a = bench.Keep<bench::CampaignBenchOptions>();
  Command c = bench.Add("campaign", "candi sfm on generated photo campaigns of N photos: seconds a stage, pairs, "
                                    "registered, camera centres against the truth, memory; the fitted law; retrieval "
                                    "recall against exhaustive matching and COLMAP's vocabulary-tree matcher");
  c.Option("--sizes", a.sizes, "Photo counts, comma separated");
  c.Option("--size", a.size, "The photos' long side, pixels").Range(64, 8192);
  c.Option("--chunks", a.chunks, "Sessions of each campaign").Range(1, 64);
  c.Option("--threads", a.threads, "Extraction and matching threads (-1: all)");
  c.Option("--recall-at", a.recall_at, "At this photo count, also match exhaustively for the recall row (0: none)");
  c.FlagOff("--no-colmap-matcher", a.colmap_side, "Do not run COLMAP's vocab_tree_matcher at --recall-at");
  c.Option("--work-dir", a.work_dir, "Folder for the campaigns and workspaces (deleted afterwards)");
  c.Flag("--keep", a.keep, "Keep the campaigns and workspaces");
  c.Option("--seed", a.seed, "Seed of the campaigns");
  c.Run([&a] { return bench::RunCampaignBench(a); });
  c.Footer("Example: candi bench campaign --sizes 50,100,200,400 --size 800 --recall-at 200");
}

}  // namespace

void AddBench(Command& root) {
  AddBenchCommand(root);
  Command bench = root.Find("bench");
  AddScaleBench(bench);
  AddViewBench(bench);
  AddSectionBench(bench);
  AddPublishBench(bench);
  AddCompareBench(bench);
  AddReliefBench(bench);
  AddCampaignBench(bench);
}

}  // namespace candi::apps
