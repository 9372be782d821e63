// candi bench dense --campaign N1,N2,...: the streaming dense stereo (photogrammetry/mvs/
// dense_stream.h) on generated photo campaigns (scenes/campaign.h) of N photos. Each campaign is
// rendered in this process and written as a dense workspace with its true cameras and a sparse
// model sampled from its true surface (no SfM: this measures the dense stage alone); `candi
// dense` runs on it as a child process, so its seconds and peak memory are its own; its cloud is
// scored against the true surface at 1, 2 and 5 cm (scenes/dense_truth.h). Then the fitted law
// and, with --grid-at N, accuracy against time for resolution scale x rounds x source views.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/child_run.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"
#include "reconstruction/photogrammetry/scenes/dense_truth.h"
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"

namespace candi::bench {

namespace pg = candi::photogrammetry;
namespace fs = std::filesystem;

namespace {

struct DenseRow {
  int photos = 0;
  double scale = 0;
  int iterations = 0, views = 0;
  double stereo = 0, filter = 0, fusion = 0, total = 0, peak_mb = 0;
  size_t points = 0, cells = 0;
  std::vector<pg::DenseTruthScore> score;
};

// The number after `key` in candi dense's summary ("stereo: ... 12.34 s" etc.); -1 when absent.
double SecondsAfter(const std::string& out, const std::string& line_start) {
  const size_t at = out.find(line_start);
  if (at == std::string::npos) return -1;
  const size_t end = out.find('\n', at);
  const std::string line = out.substr(at, end - at);
  const size_t s = line.find(" s");
  size_t begin = line.rfind(' ', s - 1);
  return std::stod(line.substr(begin + 1, s - begin - 1));
}

DenseRow RunOne(const BenchOptions& o, const std::vector<pg::SyntheticView>& views, const std::string& ws,
                double scale, int iterations, int source_views) {
  fs::remove_all(fs::path(ws) / "stereo");
  const std::string out = (fs::path(ws) / "dense.ply").string();
  std::vector<std::string> argv = {SelfPath(), "dense", ws, "-o", out, "--resolution-scale", FormatSignificant(scale, 6),
                                   "--iterations", std::to_string(iterations), "--views", std::to_string(source_views),
                                   "--threads", std::to_string(o.threads)};
  if (o.max_memory_mb > 0) argv.insert(argv.end(), {"--max-memory", std::to_string(o.max_memory_mb)});
  const ChildRun run = RunChild(argv);
  if (run.code != 0) throw std::runtime_error("candi dense failed (exit " + std::to_string(run.code) + "): " + run.out);
  DenseRow r;
  r.photos = static_cast<int>(views.size());
  r.scale = scale, r.iterations = iterations, r.views = source_views;
  r.stereo = SecondsAfter(run.out, "stereo:");
  r.filter = SecondsAfter(run.out, "filter:");
  r.fusion = SecondsAfter(run.out, "fusion:");
  r.total = run.seconds;
  r.peak_mb = run.peak_mb;
  const PointCloud cloud = io::ReadPointCloud(out);
  r.points = cloud.size();
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.WorldPosition(i));
  r.score = pg::ScoreDenseAgainstTruth(views, points, {0.01, 0.02, 0.05});
  const size_t cells = run.out.find("fusion: ");
  if (cells != std::string::npos) r.cells = std::stoul(run.out.substr(cells + 8));
  return r;
}

void PrintHeader() {
  std::printf("%6s %5s %4s %5s %9s %9s %8s %7s %10s %6s  %-17s %-17s %-17s\n", "photos", "scale", "its", "views",
              "stereo/ph", "fuse/ph", "total s", "peak MB", "points", "cells", "acc/comp/F 1 cm", "acc/comp/F 2 cm",
              "acc/comp/F 5 cm");
}

void PrintRow(const DenseRow& r) {
  std::printf("%6d %5.2f %4d %5d %9.3f %9.3f %8.1f %7.0f %10zu %6zu ", r.photos, r.scale, r.iterations, r.views,
              r.stereo / r.photos, (r.filter + r.fusion) / r.photos, r.total, r.peak_mb, r.points, r.cells);
  for (const pg::DenseTruthScore& s : r.score)
    std::printf(" %.3f/%.3f/%.3f", s.accuracy, s.completeness, s.f_score);
  std::printf("\n");
  std::fflush(stdout);
}

// The campaign of `photos` photos written as a dense workspace; the views keep their true depth
// (for the scores) and drop their pixels.
std::vector<pg::SyntheticView> MakeWorkspace(const BenchOptions& o, int photos, const std::string& ws) {
  pg::CampaignOptions c;
  c.photos = photos;
  c.width = o.campaign_size;
  std::vector<pg::SyntheticView> views = pg::RenderCampaignViews(pg::PlanCampaign(c));
  const int stride = std::max(8, o.campaign_size / 25);  // ~600 sparse points a photo
  pg::WriteDenseWorkspace(views, pg::SyntheticSparsePoints(views, stride), ws);
  for (pg::SyntheticView& v : views) v.image = Image8();
  return views;
}

}  // namespace

int RunDenseCampaign(const BenchOptions& o) {
  std::vector<int> sizes;
  for (double v : ParseNumbers(o.campaign, ',', "--campaign")) {
    if (!(v >= 8 && v <= 5000)) throw std::invalid_argument("--campaign: each a photo count in [8, 5000]");
    sizes.push_back(static_cast<int>(v));
  }
  fs::create_directories(o.work_dir);
  std::printf("candi dense on generated campaigns at %d px (true cameras, sparse points from the true surface), "
              "scale %.2f, %d rounds, %d source views, %d thread(s); stereo/ph and fuse/ph (filter + fusion) are "
              "seconds a photo; accuracy, completeness and F-score against the true surface\n",
              o.campaign_size, o.scale, o.iterations, o.views, o.threads);
  PrintHeader();
  std::vector<DenseRow> rows;
  for (int n : sizes) {
    const std::string ws = (fs::path(o.work_dir) / ("campaign_" + std::to_string(n))).string();
    fs::remove_all(ws);
    const std::vector<pg::SyntheticView> views = MakeWorkspace(o, n, ws);
    rows.push_back(RunOne(o, views, ws, o.scale, o.iterations, o.views));
    PrintRow(rows.back());
    if (n == o.grid_at) {
      std::printf("accuracy against time at %d photos:\n", n);
      PrintHeader();
      for (double scale : {0.25, 0.5, 1.0})
        for (int iterations : {2, 3})
          for (int source_views : {3, 4, 6}) PrintRow(RunOne(o, views, ws, scale, iterations, source_views));
    }
    if (!o.keep) fs::remove_all(ws);
  }
  if (rows.size() >= 2) {
    std::vector<double> n, seconds;
    for (const DenseRow& r : rows) n.push_back(r.photos), seconds.push_back(r.total);
    const auto [a, b] = FitPowerLaw(n, seconds);
    const DenseRow &first = rows.front(), &last = rows.back();
    std::printf("fitted: total seconds = %.3g x N^%.2f; seconds a photo at %d / at %d: %.2f (goal within 1.25); "
                "peak memory %.2f of it (goal within 1.2); F at 2 cm %+.1f points\n",
                a, b, last.photos, first.photos, (last.total / last.photos) / (first.total / first.photos),
                last.peak_mb / first.peak_mb, 100 * (last.score[1].f_score - first.score[1].f_score));
  }
  if (!o.keep) fs::remove_all(o.work_dir);
  return 0;
}

}  // namespace candi::bench
