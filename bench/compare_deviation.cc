// candi bench compare: the deviation methods on a known change, and C2C beside CloudCompare's
// (bench/bench.h).
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <regex>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "compare/deviation.h"
#include "core/check.h"
#include "core/rng.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/point_io.h"

namespace candi::bench {

namespace fs = std::filesystem;

namespace {

constexpr double kChange = 0.005;  // m, along the normal, inside the disc
constexpr double kNoise = 0.002;   // m, Gaussian, along the normal, both clouds
constexpr double kSpacing = 0.01;  // m, mean point spacing of each cloud
const Eigen::Vector3d kSite(416000.0, 9168000.0, 100.0);

double Height(double x, double y) { return 0.3 * std::sin(0.7 * x) + 0.2 * std::cos(0.9 * y); }
Eigen::Vector3d Normal(double x, double y) {
  return Eigen::Vector3d(-0.21 * std::cos(0.7 * x), 0.18 * std::sin(0.9 * y), 1.0).normalized();
}

struct Scene {
  double size = 0;  // the square's side, m
  PointCloud reference, compared;
  std::vector<double> truth;  // per compared point: the change along the +z normal, m
  std::vector<uint8_t> scored;  // 0 within 0.25 m of the disc's rim (the change's edge)
};

// The disc of change: centre (size/2, size/2), radius size/4.
double ChangeAt(double size, double x, double y, bool* near_rim) {
  const double r = std::hypot(x - size / 2, y - size / 2);
  if (near_rim) *near_rim = std::abs(r - size / 4) < 0.25;
  return r < size / 4 ? kChange : 0.0;
}

PointCloud Sample(uint64_t n, double size, bool changed, uint64_t seed, std::vector<double>* truth,
                  std::vector<uint8_t>* scored) {
  PointCloud c;
  c.frame.origin = kSite;
  c.positions.resize(n);
  if (truth) truth->resize(n);
  if (scored) scored->resize(n);
  Rng rng(seed);
  for (uint64_t i = 0; i < n; ++i) {
    const double x = rng.Uniform(0, size), y = rng.Uniform(0, size);
    bool near_rim = false;
    const double change = changed ? ChangeAt(size, x, y, &near_rim) : 0.0;
    c.positions[i] = Eigen::Vector3d(x, y, Height(x, y)) + (change + kNoise * rng.Normal()) * Normal(x, y);
    if (truth) (*truth)[i] = change;
    if (scored) (*scored)[i] = near_rim ? 0 : 1;
  }
  return c;
}

PointCloud Thinned(const PointCloud& c, int every) {
  PointCloud out;
  out.frame = c.frame;
  for (size_t i = 0; i < c.size(); i += static_cast<size_t>(every)) out.positions.push_back(c.positions[i]);
  return out;
}

struct Setting {
  std::string name;
  compare::DeviationOptions options;
  int thin = 1;  // the reference keeps every thin-th point
};

struct Errors {
  double rms = 0, mean_in = 0, mean_out = 0, undefined = 0;
};

Errors Score(const compare::DeviationResult& r, const Scene& s) {
  Errors e;
  double sq = 0, n = 0, in = 0, n_in = 0, out = 0, n_out = 0, undefined = 0;
  for (size_t i = 0; i < r.distance.size(); ++i) {
    if (std::isnan(r.distance[i])) {
      undefined += 1;
      continue;
    }
    if (!s.scored[i]) continue;
    const double truth = r.method == compare::Method::kC2C ? std::abs(s.truth[i]) : s.truth[i];
    sq += (r.distance[i] - truth) * (r.distance[i] - truth);
    n += 1;
    if (s.truth[i] != 0) {
      in += r.distance[i];
      n_in += 1;
    } else {
      out += r.distance[i];
      n_out += 1;
    }
  }
  e.rms = std::sqrt(sq / std::max(1.0, n));
  e.mean_in = in / std::max(1.0, n_in);
  e.mean_out = out / std::max(1.0, n_out);
  e.undefined = undefined / std::max<size_t>(1, r.distance.size());
  return e;
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string SelfExecutable() {
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  if (n <= 0) return "candi";
  buf[n] = '\0';
  return buf;
}

// Runs a shell command; returns its output (stdout and stderr) and wall seconds.
std::pair<std::string, double> Run(const std::string& command) {
  Stopwatch watch;
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot run: " + command);
  char buf[4096];
  size_t got = 0;
  while ((got = fread(buf, 1, sizeof(buf), pipe)) > 0) output.append(buf, got);
  const int status = pclose(pipe);
  if (status != 0) throw std::runtime_error("failed (" + std::to_string(status) + "): " + command + "\n" + output);
  return {output, watch.Seconds()};
}

// The sum of CloudCompare's printed "[...Distances] Time: X s" lines.
double CloudCompareDistanceSeconds(const std::string& output) {
  static const std::regex time(R"(\[(computeApproxDistances|ComputeDistances)\] Time: ([0-9.]+) s)");
  double sum = 0;
  for (auto it = std::sregex_iterator(output.begin(), output.end(), time); it != std::sregex_iterator(); ++it) {
    sum += std::stod((*it)[2]);
  }
  return sum;
}

}  // namespace

void CompareBenchOptions::Check() const {
  CANDI_CHECK_OPTION(points >= 1e3 && points <= 1e9, points, "in [1e3, 1e9]");
  CANDI_CHECK_OPTION_IN(runs, 1, 100);
}

int RunCompareBench(const CompareBenchOptions& a) {
  a.Check();
  std::vector<int> threads;
  for (double v : ParseNumbers(a.threads, ',', "--threads")) {
    if (!(v >= 1 && v <= 256)) throw std::invalid_argument("--threads: each in [1, 256]");
    threads.push_back(static_cast<int>(v));
  }
  const uint64_t n = static_cast<uint64_t>(a.points);
  Scene s;
  s.size = std::sqrt(static_cast<double>(n)) * kSpacing;
  s.reference = Sample(n, s.size, false, HashStreamKey(a.seed, 1), nullptr, nullptr);
  s.compared = Sample(n, s.size, true, HashStreamKey(a.seed, 2), &s.truth, &s.scored);
  std::printf("candi bench compare: %llu points a cloud over %.1f m x %.1f m (spacing %.0f mm), noise %.0f mm on "
              "both, a %.0f mm change in a disc; median of %d run(s)\n",
              static_cast<unsigned long long>(n), s.size, s.size, kSpacing * 1000, kNoise * 1000, kChange * 1000,
              a.runs);
  std::printf("error: RMS of (distance - truth) away from the disc's rim (C2C: against |truth|); "
              "M3C2 with max depth 0.05 m\n\n");

  bool want_c2c = false, want_m3c2 = false;
  for (const std::string& m : SplitList(a.methods)) {
    if (m == "c2c") {
      want_c2c = true;
    } else if (m == "m3c2") {
      want_m3c2 = true;
    } else {
      throw std::invalid_argument("--methods: '" + m + "'; each must be c2c or m3c2");
    }
  }
  std::vector<Setting> settings;
  auto add = [&](const std::string& name, compare::Method m, int thin = 1) {
    Setting st;
    st.name = name;
    st.options.method = m;
    st.options.m3c2.max_depth = 0.05;
    st.thin = thin;
    settings.push_back(st);
    return &settings.back().options;
  };
  add("C2C nearest point", compare::Method::kC2C);
  add("C2C local plane, k 12", compare::Method::kC2C)->c2c.local_model = compare::LocalModel::kPlane;
  {
    auto* o = add("C2C local quadric, k 20", compare::Method::kC2C);
    o->c2c.local_model = compare::LocalModel::kQuadric;
    o->c2c.model_neighbours = 20;
  }
  add("C2C nearest, reference 1/4", compare::Method::kC2C, 4);
  add("C2C plane k 12, reference 1/4", compare::Method::kC2C, 4)->c2c.local_model = compare::LocalModel::kPlane;
  for (auto [big_d, small_d] : std::vector<std::pair<double, double>>{{0.12, 0.06}, {0.24, 0.06}, {0.24, 0.12},
                                                                       {0.5, 0.1}}) {
    auto* o = add("M3C2 D " + FormatSignificant(big_d, 3) + ", d " + FormatSignificant(small_d, 3),
                  compare::Method::kM3C2);
    o->m3c2.normal_scale = big_d;
    o->m3c2.projection_scale = small_d;
  }
  {
    auto* o = add("M3C2 D 0.24, d 0.12, reference 1/4", compare::Method::kM3C2, 4);
    o->m3c2.normal_scale = 0.24;
    o->m3c2.projection_scale = 0.12;
  }

  settings.erase(std::remove_if(settings.begin(), settings.end(),
                                [&](const Setting& st) {
                                  return st.options.method == compare::Method::kC2C ? !want_c2c : !want_m3c2;
                                }),
                 settings.end());
  if (a.quick) {
    std::vector<Setting> first;
    for (const Setting& st : settings) {
      if (first.empty() || first.back().options.method != st.options.method) first.push_back(st);
    }
    settings = first;
  }
  std::printf("%-36s", "setting");
  for (int t : threads) std::printf(" %8s", (std::to_string(t) + " thr s").c_str());
  std::printf(" %10s %9s %12s %12s %10s\n", "M pts/s", "RMS mm", "in disc mm", "outside mm", "undefined");
  for (const Setting& st : settings) {
    const PointCloud reference = st.thin > 1 ? Thinned(s.reference, st.thin) : s.reference;
    std::printf("%-36s", st.name.c_str());
    std::fflush(stdout);
    double last = 0;
    compare::DeviationResult result;
    for (int t : threads) {
      compare::DeviationOptions o = st.options;
      o.threads = t;
      std::vector<double> seconds;
      for (int r = 0; r < a.runs; ++r) {
        Stopwatch watch;
        result = compare::CompareToCloud(o, reference, s.compared, "reference", "compared");
        seconds.push_back(watch.Seconds());
      }
      last = Median(seconds);
      std::printf(" %8.2f", last);
      std::fflush(stdout);
    }
    const Errors e = Score(result, s);
    std::printf(" %10.2f %9.3f %12.3f %12.3f %9.2f%%\n", n / last * 1e-6, e.rms * 1000, e.mean_in * 1000,
                e.mean_out * 1000, 100 * e.undefined);
  }

  if (!a.cloudcompare) return 0;
  if (std::system("command -v CloudCompare >/dev/null 2>&1") != 0) {
    std::printf("\nCloudCompare is not installed (Debian package cloudcompare): its column is skipped.\n");
    return 0;
  }
  const std::string dir = fs::absolute(a.work_dir).string();
  fs::create_directories(dir);
  const std::string ref_file = dir + "/reference.ply", cmp_file = dir + "/compared.ply";
  // World coordinates in the files (no shift comment, which CloudCompare does not read).
  for (const PointCloud* c : {&s.reference, &s.compared}) {
    PointCloud world = *c;
    world.Rebase(LocalFrame());
    io::WritePointCloud(c == &s.reference ? ref_file : cmp_file, world);
  }
  std::printf("\nC2C beside CloudCompare 2.11 (its defaults: octree, all cores) on the same binary PLY files, "
              "median of %d run(s):\n", a.runs);
  std::printf("%-36s %12s %14s %16s\n", "program", "end to end s", "distances s", "max |difference|");
  const std::string shift = "-GLOBAL_SHIFT -416000 -9168000 -100 ";
  std::vector<double> cc_wall, cc_dist;
  for (int r = 0; r < a.runs; ++r) {
    const auto [output, wall] =
        Run("env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -AUTO_SAVE OFF -C_EXPORT_FMT PLY -O " +
            shift + cmp_file + " -O " + shift + ref_file + " -C2C_DIST -SAVE_CLOUDS FILE \"" + dir +
            "/cc_compared.ply " + dir + "/cc_reference.ply\"");
    cc_wall.push_back(wall);
    cc_dist.push_back(CloudCompareDistanceSeconds(output));
  }
  const PointCloud cc = io::ReadPointCloud(dir + "/cc_compared.ply");
  const ScalarField* cc_field = cc.FindScalar("C2C_absolute_distances");
  std::printf("%-36s %12.2f %14.2f %16s\n", "CloudCompare -C2C_DIST", Median(cc_wall), Median(cc_dist), "");
  for (int t : threads) {
    std::vector<double> wall, dist;
    for (int r = 0; r < a.runs; ++r) {
      const auto [output, seconds] = Run(SelfExecutable() + " -q compare " + ref_file + " " + cmp_file + " -o " +
                                         dir + "/candi.ply --threads " + std::to_string(t));
      wall.push_back(seconds);
      compare::DeviationOptions o;
      o.threads = t;
      Stopwatch watch;
      compare::CompareToCloud(o, s.reference, s.compared, "reference", "compared");
      dist.push_back(watch.Seconds());
    }
    const PointCloud mine = io::ReadPointCloud(dir + "/candi.ply");
    double worst = 0;
    if (cc_field && cc.size() == mine.size()) {
      const ScalarField* f = mine.FindScalar("distance");
      for (size_t i = 0; i < mine.size(); ++i) worst = std::max(worst, std::abs(f->Get(i) - cc_field->Get(i)));
    }
    std::printf("%-36s %12.2f %14.2f %16s\n", ("candi compare, " + std::to_string(t) + " thread(s)").c_str(),
                Median(wall), Median(dist), (FormatSignificant(worst * 1e6, 3) + " um").c_str());
  }
  std::printf("\nEnd to end: reading both files, the distances, writing the compared cloud with its field (candi "
              "also writes its summary, histogram and report). Distances: CloudCompare's printed times of its "
              "distance step (its octree built before); candi's CompareToCloud (its point tree's build included).\n");
  return 0;
}

}  // namespace candi::bench
