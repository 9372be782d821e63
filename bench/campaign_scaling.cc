// candi bench campaign: candi sfm on generated campaigns of N photos (bench/bench.h): seconds a
// stage, pairs, photos registered, camera centres against the truth, peak memory; the fitted law
// of time against N; at one N the retrieval's recall of the pairs exhaustive matching verifies,
// and COLMAP's own vocabulary-tree matcher on the same features.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "core/check.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"
#include "reconstruction/photogrammetry/sfm/sift_matching.h"

namespace candi::bench {

namespace fs = std::filesystem;
namespace pg = candi::photogrammetry;

void CampaignBenchOptions::Check() const {
  CANDI_CHECK_OPTION_IN(size, 64, 8192);
  CANDI_CHECK_OPTION_IN(chunks, 1, 64);
  CANDI_CHECK_OPTION(threads == -1 || (threads >= 1 && threads <= 256), threads, "-1 (all) or [1, 256]");
  CANDI_CHECK_OPTION_GE(recall_at, 0);
  CANDI_CHECK_OPTION_MSG(!work_dir.empty(), work_dir, "must name a folder");
}

namespace {

double PeakMb(int who) {
  rusage u{};
  getrusage(who, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // kB on Linux
}

double StageSeconds(const pg::SfmSummary& s, const std::string& stage) {
  double total = 0;
  for (const auto& [name, seconds] : s.stage_seconds)
    if (name == stage) total += seconds;
  return total;
}

// The model's camera centres against the campaign's truth after one similarity (the model's frame
// is its own): RMS, metres; +inf with fewer than three registered.
double CentreRms(const pg::ColmapModel& model, const pg::Campaign& campaign) {
  std::vector<Eigen::Vector3d> source, target;
  for (const auto& [id, image] : model.images) {
    const std::string file = fs::path(image.name).filename().string();
    for (const pg::CampaignPhoto& p : campaign.photos) {
      if (p.name != file) continue;
      source.push_back(-(image.cam_from_world_rotation.conjugate() * image.cam_from_world_translation));
      target.push_back(p.camera.Center());
    }
  }
  if (source.size() < 3) return std::numeric_limits<double>::infinity();
  const Sim3 fit = pg::UmeyamaSimilarity(source, target, std::vector<double>(source.size(), 1.0), true);
  double sum = 0;
  for (size_t k = 0; k < source.size(); ++k) sum += (fit * source[k] - target[k]).squaredNorm();
  return std::sqrt(sum / source.size());
}

struct Row {
  int photos = 0;
  size_t registered = 0, pairs = 0, verified = 0;
  double extract = 0, match = 0, verify = 0, transitive = 0, map = 0, undistort = 0, total = 0, rms = 0;
  double candi_mb = 0, colmap_mb = 0;
};

pg::SfmSummary RunOne(const CampaignBenchOptions& o, const std::string& site, const std::string& work,
                      pg::PairStrategy strategy) {
  pg::SfmOptions sfm;
  sfm.threads = o.threads;
  sfm.max_image_size = o.size;
  sfm.pairs.strategy = strategy;
  sfm.overwrite = true;
  return pg::RunSfm(sfm, site, work, [](const std::string& stage, int index, int count, double seconds, bool done,
                                        double) {
    if (done) std::fprintf(stderr, "  [%d/%d] %s %.1f s\n", index, count, stage.c_str(), seconds);
  });
}

}  // namespace

std::pair<double, double> FitPowerLaw(const std::vector<double>& n, const std::vector<double>& seconds) {
  // Least squares in logs.
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t k = 0; k < n.size(); ++k) {
    const double x = std::log(n[k]), y = std::log(seconds[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double m = static_cast<double>(n.size());
  const double b = (m * sxy - sx * sy) / (m * sxx - sx * sx);
  return {std::exp((sy - b * sx) / m), b};
}

int RunCampaignBench(const CampaignBenchOptions& o) {
  o.Check();
  std::vector<int> sizes;
  for (double v : ParseNumbers(o.sizes, ',', "--sizes")) {
    if (!(v >= 8 && v <= 5000)) throw std::invalid_argument("--sizes: each a photo count in [8, 5000]");
    sizes.push_back(static_cast<int>(v));
  }
  fs::create_directories(o.work_dir);
  std::vector<Row> rows;
  std::printf("candi bench campaign: candi sfm (auto matching, one piece) on campaigns of %d px photos in %d "
              "sessions\n", o.size, o.chunks);
  std::printf("%6s %10s %7s %8s %8s %8s %8s %8s %8s %8s %8s %8s %9s %9s %9s\n", "photos", "registered", "pairs",
              "verified", "extract", "match", "verify", "transit", "map", "undist", "total s", "s/photo", "centre mm",
              "candi MB", "COLMAP MB");
  for (int n : sizes) {
    pg::CampaignOptions c;
    c.photos = n;
    c.width = o.size;
    c.chunks = o.chunks;
    c.seed = o.seed;
    const std::string site = o.work_dir + "/site_" + std::to_string(n);
    std::fprintf(stderr, "campaign of %d photos ...\n", n);
    const pg::Campaign campaign = pg::WriteCampaign(c, site, true);
    Row r;
    r.photos = n;
    const pg::SfmSummary s = RunOne(o, site, o.work_dir + "/sfm_" + std::to_string(n), pg::PairStrategy::kAuto);
    r.registered = s.registered.size();
    r.pairs = s.pairs_tried;
    r.verified = s.pairs_verified;
    r.extract = StageSeconds(s, "feature_extractor");
    r.match = StageSeconds(s, pg::kMatchStage);
    r.verify = StageSeconds(s, "matches_importer");
    r.transitive = StageSeconds(s, pg::kTransitiveStage);
    r.map = StageSeconds(s, "mapper");
    r.undistort = StageSeconds(s, "image_undistorter");
    r.total = r.extract + r.match + r.verify + r.transitive + r.map + r.undistort;
    r.rms = CentreRms(pg::ReadColmapModel(s.model_dir), campaign);
    r.candi_mb = PeakMb(RUSAGE_SELF);
    r.colmap_mb = PeakMb(RUSAGE_CHILDREN);
    rows.push_back(r);
    std::printf("%6d %9.1f%% %7zu %8zu %8.1f %8.1f %8.1f %8.1f %8.1f %8.1f %8.1f %8.3f %9.1f %9.0f %9.0f\n", n,
                100.0 * r.registered / n, r.pairs, r.verified, r.extract, r.match, r.verify, r.transitive, r.map,
                r.undistort, r.total, r.total / n, 1e3 * r.rms, r.candi_mb, r.colmap_mb);
    std::fflush(stdout);

    if (n == o.recall_at) {
      // The pairs exhaustive matching verifies, and how many of them the chosen pairs hold.
      const std::string work = o.work_dir + "/sfm_" + std::to_string(n) + "_exhaustive";
      const pg::SfmSummary e = RunOne(o, site, work, pg::PairStrategy::kExhaustive);
      // The pairs with matches: before transitive matching (matches.txt), and in all (the database).
      const std::string chosen_dir = o.work_dir + "/sfm_" + std::to_string(n);
      const auto first = pg::MatchListPairs(chosen_dir + "/matches.txt");
      const auto chosen = pg::MatchedPairNames(chosen_dir + "/database.db");
      const auto verified = pg::VerifiedPairNames(work + "/database.db");
      size_t found = 0, found_first = 0;
      for (const auto& p : verified) found += chosen.count(p), found_first += first.count(p);
      const auto percent = [&](size_t k) { return verified.empty() ? 0.0 : 100.0 * k / verified.size(); };
      std::printf("  recall at %d photos: the %zu chosen pairs with matches hold %zu of the %zu that exhaustive matching "
                  "(%zu pairs) verifies: %.1f%% (%.1f%% before transitive matching, %zu pairs); exhaustive matching + "
                  "verification %.1f s, chosen %.1f s\n",
                  n, chosen.size(), found, verified.size(), e.pairs_tried, percent(found), percent(found_first),
                  first.size(), StageSeconds(e, pg::kMatchStage) + StageSeconds(e, "matches_importer"),
                  r.match + r.verify + r.transitive);
      if (o.colmap_side) {
        // COLMAP's own retrieval on the same features: a tree trained on them, 20 neighbours.
        const std::string db = work + "/colmap_vocab.db";
        fs::copy_file(o.work_dir + "/sfm_" + std::to_string(n) + "/database.db", db,
                      fs::copy_options::overwrite_existing);
        pg::ClearMatches(db);
        Stopwatch watch;
        const int built = pg::RunLogged({"colmap", "vocab_tree_builder", "--database_path", db, "--vocab_tree_path",
                                         work + "/vocab_tree.bin", "--num_visual_words", "4096"},
                                        work + "/vocab_tree_builder.log");
        const double build_s = watch.Seconds();
        watch.Restart();
        const int matched = pg::RunLogged({"colmap", "vocab_tree_matcher", "--database_path", db,
                                           "--VocabTreeMatching.vocab_tree_path", work + "/vocab_tree.bin",
                                           "--VocabTreeMatching.num_images", "20", "--SiftMatching.use_gpu", "0"},
                                          work + "/vocab_tree_matcher.log");
        const double match_s = watch.Seconds();
        if (built != 0 || matched != 0) {
          std::printf("  COLMAP's vocab_tree_builder / vocab_tree_matcher failed (exit %d / %d; logs in %s)\n", built,
                      matched, work.c_str());
        } else {
          const auto colmap_verified = pg::VerifiedPairNames(db);
          size_t colmap_found = 0;
          for (const auto& p : verified) colmap_found += colmap_verified.count(p);
          std::printf("  COLMAP's vocab_tree_matcher (its tree of 4,096 words trained on these features in %.1f s, "
                      "20 neighbours): %.1f s, %zu pairs verified, recall %.1f%%\n", build_s, match_s,
                      colmap_verified.size(), verified.empty() ? 0.0 : 100.0 * colmap_found / verified.size());
        }
      }
    }
  }
  if (rows.size() >= 2) {
    std::vector<double> n, seconds;
    for (const Row& r : rows) n.push_back(r.photos), seconds.push_back(r.total);
    const auto [a, b] = FitPowerLaw(n, seconds);
    std::printf("fitted: total seconds = %.3g x N^%.2f; seconds a photo at %d photos / at %d: %.2f (goal <= 1.5)\n", a,
                b, rows.back().photos, rows.front().photos,
                (rows.back().total / rows.back().photos) / (rows.front().total / rows.front().photos));
  }
  if (!o.keep) fs::remove_all(o.work_dir);
  return 0;
}

}  // namespace candi::bench
