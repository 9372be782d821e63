// Many-scan registration: pairwise ICP (registration.h), a spanning tree for the start of the
// global solve, then Ceres over all poses with point-to-plane correspondences re-found each
// round (the "ICP on the pose graph" of e.g. Pulli, "Multiview registration for large data sets",
// 3DIM 1999, with the pairs' points rather than their relative poses as constraints, so each
// pair is weighted by the geometry it shares and a loop's error is spread where the points allow).
#include "reconstruction/photogrammetry/registration/multi_registration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <utility>

#include "core/check.h"
#include "core/parallel.h"
#include "core/text_format.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"
#include "reconstruction/photogrammetry/registration/local_points.h"
#include "reconstruction/photogrammetry/registration/point_index.h"
#include "reconstruction/photogrammetry/registration/point_normals.h"
#include "reconstruction/photogrammetry/registration/registration.h"

namespace candi::photogrammetry {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kMoveTolerance = 1e-5;  // m: a round that moves no pose more has converged
constexpr double kTurnTolerance = 1e-6;  // rad

// A scan prepared once: thinned points and their normals in the scan's frame, and a kd-tree of
// them (float, relative to `origin`, the rounded centre of the scan's box).
struct Scan {
  std::vector<Eigen::Vector3d> points, normals;  // normals NaN where no plane is defined
  std::vector<size_t> icp_subset;                // the points ICP works on (icp_voxel)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Box3d box;
  std::unique_ptr<PointIndex> index;
};

// A pose in the common local frame: world = R x + t + O. Quaternion in Eigen's (x, y, z, w).
struct Pose {
  double q[4];
  double t[3];
};

Pose ToPose(const Rigid3& world, const Eigen::Vector3d& origin) {
  Pose p;
  const Eigen::Quaterniond q = world.rotation.normalized();
  std::copy(q.coeffs().data(), q.coeffs().data() + 4, p.q);
  const Eigen::Vector3d t = world.translation - origin;
  std::copy(t.data(), t.data() + 3, p.t);
  return p;
}

Rigid3 ToRigid(const Pose& p, const Eigen::Vector3d& origin) {
  return Rigid3(Eigen::Quaterniond(p.q[3], p.q[0], p.q[1], p.q[2]),
                Eigen::Vector3d(p.t[0], p.t[1], p.t[2]) + origin);
}

// The same pose with translation relative to the origin (the arithmetic of composition stays
// small at survey coordinates).
Rigid3 LocalRigid(const Pose& p) {
  return Rigid3(Eigen::Quaterniond(p.q[3], p.q[0], p.q[1], p.q[2]),
                Eigen::Vector3d(p.t[0], p.t[1], p.t[2]));
}

Pose FromLocalRigid(const Rigid3& r) { return ToPose(r, Eigen::Vector3d::Zero()); }

double AngleDeg(const Eigen::Quaterniond& q) {
  return Eigen::AngleAxisd(q.normalized()).angle() * kDegPerRad;
}

void CheckInput(const MultiRegistrationOptions& o, const std::vector<PointCloud>& scans,
                const std::vector<Rigid3>& poses, const std::vector<ScanTarget>& targets) {
  if (scans.empty()) throw InputError("scans", "", "no scans to register");
  if (poses.size() != scans.size()) {
    throw InputError(
        "start poses", "",
        std::to_string(poses.size()) + " poses for " + std::to_string(scans.size()) + " scans");
  }
  const int n = static_cast<int>(scans.size());
  for (int i = 0; i < n; ++i) {
    const std::string name = "scan " + std::to_string(i);
    if (scans[i].empty()) throw InputError(name, "", "no points");
    scans[i].CheckConsistent();
    CheckFinitePositions(scans[i], name);
    if (!poses[i].translation.allFinite() || !poses[i].rotation.coeffs().allFinite() ||
        poses[i].rotation.norm() < 0.5) {
      throw InputError("start poses", "pose " + std::to_string(i), "not a finite rigid transform");
    }
  }
  for (int f : o.fixed_scans) {
    if (f < 0 || f >= n) {
      throw InputError(
          "MultiRegistrationOptions::fixed_scans", "",
          "scan index " + std::to_string(f) + " out of range [0, " + std::to_string(n) + ")");
    }
  }
  for (size_t k = 0; k < targets.size(); ++k) {
    const ScanTarget& t = targets[k];
    const std::string where = "target " + std::to_string(k) + " '" + t.name + "'";
    if (t.scan < 0 || t.scan >= n) {
      throw InputError(
          "targets", where,
          "scan index " + std::to_string(t.scan) + " out of range [0, " + std::to_string(n) + ")");
    }
    if (!t.in_scan.allFinite() || !t.world.allFinite()) {
      throw InputError("targets", where, "coordinates are not finite");
    }
    if (!(t.accuracy > 0) || !std::isfinite(t.accuracy)) {
      throw InputError("targets", where, "accuracy must be finite and > 0");
    }
  }
}

Scan PrepareScan(const MultiRegistrationOptions& o, const PointCloud& cloud) {
  std::vector<size_t> idx;
  if (o.voxel > 0) {
    idx = VoxelThinIndices(cloud, o.voxel);
  } else {
    idx.resize(cloud.size());
    for (size_t i = 0; i < idx.size(); ++i) idx[i] = i;
  }
  Scan s;
  s.points.reserve(idx.size());
  for (size_t i : idx) {
    s.points.push_back(cloud.WorldPosition(i));
    s.box.Extend(s.points.back());
  }
  s.origin = CommonOrigin(s.box);
  std::vector<Eigen::Vector3f> local(s.points.size());
  for (size_t i = 0; i < local.size(); ++i) local[i] = (s.points[i] - s.origin).cast<float>();
  const std::vector<Eigen::Vector3f> normals = EstimateNormals(local, o.normal_neighbours);
  s.normals.resize(normals.size());
  for (size_t i = 0; i < normals.size(); ++i) {
    const Eigen::Vector3f& n = normals[i];
    s.normals[i] = n.allFinite() && n.squaredNorm() > 0.25f ? n.cast<double>().normalized()
                                                            : Eigen::Vector3d::Constant(kNaN);
  }
  s.index = std::make_unique<PointIndex>(local);
  if (o.icp_voxel > 0) {
    PointCloud thin;
    thin.positions = s.points;
    s.icp_subset = VoxelThinIndices(thin, o.icp_voxel);
  } else {
    s.icp_subset.resize(s.points.size());
    for (size_t i = 0; i < s.icp_subset.size(); ++i) s.icp_subset[i] = i;
  }
  return s;
}

Box3d WorldBox(const Scan& s, const Rigid3& pose, double grow) {
  Box3d out;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d x((c & 1) ? s.box.max.x() : s.box.min.x(),
                            (c & 2) ? s.box.max.y() : s.box.min.y(),
                            (c & 4) ? s.box.max.z() : s.box.min.z());
    out.Extend(pose * x);
  }
  out.min.array() -= grow;
  out.max.array() += grow;
  return out;
}

bool Intersect(const Box3d& a, const Box3d& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

// The scan's points (all, or ICP's subset), with normals, moved by `local_pose`: world
// coordinates relative to the common origin (RegisterPointClouds takes them as they are).
PointCloud WorldCloud(const Scan& s, const Rigid3& local_pose, bool icp_subset) {
  std::vector<size_t> all;
  if (!icp_subset) {
    all.resize(s.points.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  }
  const std::vector<size_t>& subset = icp_subset ? s.icp_subset : all;
  PointCloud c;
  PointSchema schema;
  schema.normals = true;
  c.SetSchema(schema);
  c.Resize(subset.size());
  const Eigen::Matrix3d r = local_pose.rotation.toRotationMatrix();
  for (size_t k = 0; k < subset.size(); ++k) {
    const size_t i = subset[k];
    c.positions[k] = r * s.points[i] + local_pose.translation;
    c.normals[k] = (r * s.normals[i]).cast<float>();
  }
  return c;
}

struct PairWork {
  int a = 0, b = 0;  // moving a, fixed b
  Rigid3 b_from_a;   // the pairwise ICP's relative pose (scan frames)
  PairReport report;
};

void RefinePair(const MultiRegistrationOptions& o, const std::vector<Scan>& scans,
                const std::vector<Pose>& start, PairWork* w) {
  const Rigid3 ta = LocalRigid(start[w->a]), tb = LocalRigid(start[w->b]);
  // The moving scan's ICP subset onto all the fixed scan's points: ICP's cost goes with the
  // moving points, and the overlap within solve_distance needs the fixed scan's full density.
  const PointCloud moving = WorldCloud(scans[w->a], ta, true);
  const PointCloud fixed = WorldCloud(scans[w->b], tb, false);
  RegistrationOptions icp;
  icp.max_correspondence_distance = o.max_correspondence_distance;
  icp.max_iterations = o.icp_iterations;
  icp.normal_neighbours = o.normal_neighbours;
  const RegistrationResult coarse = RegisterPointClouds(icp, moving, fixed);
  PairReport& r = w->report;
  r.moving = w->a;
  r.fixed = w->b;
  r.rms_before = coarse.rms_before;
  r.rms_after = r.rms_global = kNaN;
  if (coarse.status == RegistrationStatus::kNoOverlap) {
    r.reason = "coarse ICP: " + coarse.message;
    return;
  }
  icp.max_correspondence_distance = o.solve_distance;
  icp.initial = coarse.fixed_from_moving;
  const RegistrationResult fine = RegisterPointClouds(icp, moving, fixed);
  r.overlap = fine.overlap_after;
  r.rms_after = fine.rms_after;
  w->b_from_a = tb.Inverse() * fine.fixed_from_moving * ta;
  if (fine.status == RegistrationStatus::kNoOverlap) {
    r.reason = "fine ICP: " + fine.message;
  } else if (!(fine.overlap_after >= o.min_overlap)) {
    r.reason = "overlap " + FormatDouble(fine.overlap_after) + " < min_overlap " +
               FormatDouble(o.min_overlap);
  } else {
    r.accepted = true;
    r.reason = fine.converged() ? "accepted" : "accepted (fine ICP: " + fine.message + ")";
  }
}

// The accepted-pair graph's spanning forest grown from `roots` by largest overlap first (Prim);
// parent[i] = -1 for roots and for scans the roots do not reach, edge[i] = the pair that joined i.
struct Forest {
  std::vector<int> parent, edge, root, depth;
  std::vector<bool> in;
};

Forest GrowForest(int n, const std::vector<PairWork>& pairs, const std::vector<int>& roots) {
  Forest f{std::vector<int>(n, -1), std::vector<int>(n, -1), std::vector<int>(n, -1),
           std::vector<int>(n, 0), std::vector<bool>(n, false)};
  for (int r : roots) f.in[r] = true, f.root[r] = r;
  for (;;) {
    int best = -1;
    for (size_t k = 0; k < pairs.size(); ++k) {
      const PairWork& p = pairs[k];
      if (!p.report.accepted || f.in[p.a] == f.in[p.b]) continue;
      if (best < 0 || p.report.overlap > pairs[best].report.overlap) best = static_cast<int>(k);
    }
    if (best < 0) return f;
    const PairWork& p = pairs[best];
    const int from = f.in[p.a] ? p.a : p.b, to = f.in[p.a] ? p.b : p.a;
    f.in[to] = true;
    f.parent[to] = from;
    f.edge[to] = best;
    f.root[to] = f.root[from];
    f.depth[to] = f.depth[from] + 1;
  }
}

// y_from_x from the pair's ICP (x, y its two scans).
Rigid3 PairTransform(const PairWork& p, int x, int y) {
  return x == p.a ? p.b_from_a : p.b_from_a.Inverse();
}

struct Correspondence {
  int src, dst;             // scans
  Eigen::Vector3d p, q, n;  // p in src's frame; q and its normal n in dst's frame
  int pair;                 // index into the pairs
};

// Point-to-plane residual n_b . (T_a p - T_b q), with n rotated into the common frame.
struct PointToPlane {
  Eigen::Vector3d p, q, n;
  template <typename T>
  bool operator()(const T* qa, const T* ta, const T* qb, const T* tb, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> ra(qa), rb(qb);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> va(ta), vb(tb);
    const Eigen::Matrix<T, 3, 1> xa = ra * p.cast<T>() + va, xb = rb * q.cast<T>() + vb;
    r[0] = (rb * n.cast<T>()).dot(xa - xb);
    return true;
  }
  static ceres::CostFunction* Create(const Correspondence& c) {
    return new ceres::AutoDiffCostFunction<PointToPlane, 1, 4, 3, 4, 3>(
        new PointToPlane{c.p, c.q, c.n});
  }
};

struct TargetTerm {
  Eigen::Vector3d p, w;  // in the scan's frame; world minus the origin
  double inv_sigma;
  template <typename T>
  bool operator()(const T* q, const T* t, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> rq(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> vt(t);
    const Eigen::Matrix<T, 3, 1> e = (rq * p.cast<T>() + vt - w.cast<T>()) * T(inv_sigma);
    r[0] = e[0], r[1] = e[1], r[2] = e[2];
    return true;
  }
};

std::vector<Correspondence> FindCorrespondences(const MultiRegistrationOptions& o,
                                                const std::vector<Scan>& scans,
                                                const std::vector<Pose>& poses,
                                                const std::vector<PairWork>& pairs,
                                                const std::vector<bool>& solved) {
  std::vector<Correspondence> out;
  const double max_sq = o.solve_distance * o.solve_distance;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const PairWork& pw = pairs[k];
    if (!pw.report.accepted || !solved[pw.a] || !solved[pw.b]) continue;
    for (const auto& [src, dst] : {std::pair{pw.a, pw.b}, std::pair{pw.b, pw.a}}) {
      const Rigid3 dst_from_src = LocalRigid(poses[dst]).Inverse() * LocalRigid(poses[src]);
      const Scan& s = scans[src];
      const Scan& d = scans[dst];
      const size_t stride =
          std::max<size_t>(1, (s.points.size() + o.correspondences_per_pair - 1) /
                                  static_cast<size_t>(o.correspondences_per_pair));
      for (size_t i = 0; i < s.points.size(); i += stride) {
        const Eigen::Vector3d x = dst_from_src * s.points[i];
        const auto [j, d2] = d.index->Nearest(x - d.origin);
        if (j < 0 || d2 > max_sq || !d.normals[j].allFinite()) continue;
        out.push_back({src, dst, s.points[i], d.points[j], d.normals[j], static_cast<int>(k)});
      }
    }
  }
  return out;
}

double PlaneDistance(const Correspondence& c, const std::vector<Pose>& poses) {
  const Rigid3 ta = LocalRigid(poses[c.src]), tb = LocalRigid(poses[c.dst]);
  return (tb.rotation * c.n).dot(ta * c.p - tb * c.q);
}

// One round: Ceres over the poses of the solved scans. Returns false when Ceres fails.
bool SolveRound(const MultiRegistrationOptions& o, const std::vector<Correspondence>& corr,
                const std::vector<ScanTarget>& targets, const Eigen::Vector3d& origin,
                const std::vector<bool>& solved, const std::vector<bool>& held,
                std::vector<Pose>* poses, std::string* message) {
  ceres::Problem problem;
  std::vector<Pose>& p = *poses;
  for (const Correspondence& c : corr) {
    problem.AddResidualBlock(PointToPlane::Create(c), new ceres::HuberLoss(o.loss_scale),
                             p[c.src].q, p[c.src].t, p[c.dst].q, p[c.dst].t);
  }
  for (const ScanTarget& t : targets) {
    if (t.role != TargetRole::kControl || !solved[t.scan]) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TargetTerm, 3, 4, 3>(
                                 new TargetTerm{t.in_scan, t.world - origin, 1.0 / t.accuracy}),
                             nullptr, p[t.scan].q, p[t.scan].t);
  }
  for (size_t i = 0; i < p.size(); ++i) {
    if (!solved[i] || !problem.HasParameterBlock(p[i].q)) continue;
    problem.SetManifold(p[i].q, new ceres::EigenQuaternionManifold);
    if (held[i]) {
      problem.SetParameterBlockConstant(p[i].q);
      problem.SetParameterBlockConstant(p[i].t);
    }
  }
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver.max_num_iterations = 50;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.function_tolerance = 1e-12;
  solver.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    *message = "global solve failed: " + summary.message;
    return false;
  }
  return true;
}

void FillRmse(const std::vector<Eigen::Vector3d>& residuals, const std::vector<ScanTarget>& targets,
              TargetRole role, Rmse* out) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t k = 0; k < targets.size(); ++k) {
    if (targets[k].role != role || !residuals[k].allFinite()) continue;
    sum += residuals[k].cwiseAbs2();
    ++n;
  }
  out->count = n;
  if (n == 0) return;
  out->x = std::sqrt(sum.x() / n);
  out->y = std::sqrt(sum.y() / n);
  out->z = std::sqrt(sum.z() / n);
  out->xy = std::sqrt((sum.x() + sum.y()) / n);
  out->d3 = std::sqrt(sum.sum() / n);
}

// The accepted pair's relative pose refined by the global solve's own terms on the two scans
// alone (robust, unlike ICP's least squares): `pair_rounds` rounds with the fixed scan held.
void RefinePairRobustly(const MultiRegistrationOptions& o, const std::vector<Scan>& scans,
                        const std::vector<Pose>& start, PairWork* w) {
  if (!w->report.accepted || o.pair_rounds == 0) return;
  const int n = static_cast<int>(scans.size());
  std::vector<Pose> poses = start;
  poses[w->a] = FromLocalRigid(LocalRigid(start[w->b]) * w->b_from_a);
  std::vector<bool> solved(n, false), held(n, false);
  solved[w->a] = solved[w->b] = held[w->b] = true;
  const std::vector<PairWork> one = {*w};
  std::string message;
  for (int round = 0; round < o.pair_rounds; ++round) {
    const std::vector<Correspondence> corr = FindCorrespondences(o, scans, poses, one, solved);
    if (corr.size() < 6 ||
        !SolveRound(o, corr, {}, Eigen::Vector3d::Zero(), solved, held, &poses, &message)) {
      return;  // keep the ICP's result
    }
  }
  w->b_from_a = LocalRigid(poses[w->b]).Inverse() * LocalRigid(poses[w->a]);
}

// The loop closed by each accepted pair off the forest whose ends share a root.
std::vector<LoopReport> FindLoops(const std::vector<PairWork>& pairs, const Forest& f) {
  std::vector<LoopReport> out;
  for (size_t k = 0; k < pairs.size(); ++k) {
    const PairWork& p = pairs[k];
    if (!p.report.accepted || !f.in[p.a] || !f.in[p.b] || f.root[p.a] != f.root[p.b]) continue;
    if (f.edge[p.a] == static_cast<int>(k) || f.edge[p.b] == static_cast<int>(k)) continue;
    std::vector<int> up, down;  // a up to the common ancestor; b up to it (reversed later)
    int u = p.a, v = p.b;
    while (u != v) {
      if (f.depth[u] >= f.depth[v])
        up.push_back(u), u = f.parent[u];
      else
        down.push_back(v), v = f.parent[v];
    }
    LoopReport loop;
    loop.scans = up;
    loop.scans.push_back(u);
    loop.scans.insert(loop.scans.end(), down.rbegin(), down.rend());
    Rigid3 m;  // around the cycle: a -> ... -> b -> a
    for (size_t s = 0; s + 1 < loop.scans.size(); ++s) {
      const int x = loop.scans[s], y = loop.scans[s + 1];
      const int e = f.parent[x] == y ? f.edge[x] : f.edge[y];
      m = PairTransform(pairs[e], x, y) * m;
    }
    m = PairTransform(p, p.b, p.a) * m;
    loop.translation = m.translation.norm();
    loop.rotation_deg = AngleDeg(m.rotation);
    out.push_back(loop);
  }
  return out;
}

std::vector<PairWork> CandidatePairs(const MultiRegistrationOptions& o,
                                     const std::vector<Scan>& scans,
                                     const std::vector<Pose>& start) {
  std::vector<PairWork> pairs;
  const int n = static_cast<int>(scans.size());
  for (int a = 0; a < n; ++a) {
    const Box3d ba = WorldBox(scans[a], LocalRigid(start[a]), o.max_correspondence_distance);
    for (int b = a + 1; b < n; ++b) {
      if (Intersect(ba, WorldBox(scans[b], LocalRigid(start[b]), 0)))
        pairs.push_back({a, b, {}, {}});
    }
  }
  return pairs;
}

// Where the global solve starts: which scans it holds, the spanning forest from the anchors and
// the poses along it.
struct Start {
  Forest forest;
  std::vector<bool> held;
  std::vector<Pose> poses;
};

int CountControls(const std::vector<ScanTarget>& targets) {
  int controls = 0;
  for (const ScanTarget& t : targets) controls += t.role == TargetRole::kControl;
  return controls;
}

// Moves the forest's poses rigidly onto the control targets it holds (Umeyama, no scale); false
// when it holds fewer than 3.
bool MoveOntoTargets(const std::vector<ScanTarget>& targets, const Eigen::Vector3d& origin,
                     Start* s) {
  Eigen::Matrix3Xd src(3, 0), dst(3, 0);
  for (const ScanTarget& t : targets) {
    if (t.role != TargetRole::kControl || !s->forest.in[t.scan]) continue;
    src.conservativeResize(3, src.cols() + 1);
    dst.conservativeResize(3, dst.cols() + 1);
    src.col(src.cols() - 1) = LocalRigid(s->poses[t.scan]) * t.in_scan;
    dst.col(dst.cols() - 1) = t.world - origin;
  }
  if (src.cols() < 3) return false;
  const Eigen::Matrix4d m = Eigen::umeyama(src, dst, false);
  const Rigid3 move(Eigen::Quaterniond(Eigen::Matrix3d(m.topLeftCorner<3, 3>())),
                    m.topRightCorner<3, 1>());
  for (size_t i = 0; i < s->poses.size(); ++i) {
    if (s->forest.in[i]) s->poses[i] = FromLocalRigid(move * LocalRigid(s->poses[i]));
  }
  return true;
}

// Anchors: the fixed scans; else, with >= 3 control targets, the first scan holding one (the
// targets then fix the frame); else scan 0, held.
Start StartPoses(const MultiRegistrationOptions& o, const std::vector<PairWork>& pairs,
                 const std::vector<ScanTarget>& targets, const std::vector<Pose>& start,
                 const Eigen::Vector3d& origin) {
  const int n = static_cast<int>(start.size());
  Start s;
  s.held.assign(n, false);
  std::vector<int> roots(o.fixed_scans.begin(), o.fixed_scans.end());
  std::sort(roots.begin(), roots.end());
  roots.erase(std::unique(roots.begin(), roots.end()), roots.end());
  for (int f : roots) s.held[f] = true;
  const bool by_targets = roots.empty() && CountControls(targets) >= 3;
  if (roots.empty()) {
    int first = by_targets ? n : 0;
    for (const ScanTarget& t : targets) {
      if (by_targets && t.role == TargetRole::kControl) first = std::min(first, t.scan);
    }
    roots.push_back(first);
  }
  s.forest = GrowForest(n, pairs, roots);
  s.poses = start;
  for (int depth = 1; depth < n; ++depth) {  // parents before children
    for (int i = 0; i < n; ++i) {
      if (!s.forest.in[i] || s.forest.depth[i] != depth) continue;
      const int parent = s.forest.parent[i];
      s.poses[i] = FromLocalRigid(LocalRigid(s.poses[parent]) *
                                  PairTransform(pairs[s.forest.edge[i]], i, parent));
    }
  }
  // Without fixed scans the root is held unless >= 3 control targets in its component fix it.
  if (o.fixed_scans.empty() && !(by_targets && MoveOntoTargets(targets, origin, &s))) {
    s.held[roots[0]] = true;
  }
  return s;
}

// The global rounds; returns the correspondences of the final poses.
std::vector<Correspondence> GlobalRounds(const MultiRegistrationOptions& o,
                                         const std::vector<Scan>& scans,
                                         const std::vector<PairWork>& pairs,
                                         const std::vector<ScanTarget>& targets,
                                         const ProgressCallback& progress, Start* s,
                                         MultiRegistrationResult* result) {
  std::vector<Pose>& poses = s->poses;
  for (int round = 0; round < o.outer_iterations; ++round) {
    const std::vector<Correspondence> corr =
        FindCorrespondences(o, scans, poses, pairs, s->forest.in);
    const std::vector<Pose> before = poses;
    if (!SolveRound(o, corr, targets, result->origin, s->forest.in, s->held, &poses,
                    &result->message)) {
      poses = before;
      break;
    }
    ++result->outer_iterations;
    if (progress) progress(pairs.size() + round + 1, pairs.size() + o.outer_iterations);
    double move = 0, turn = 0;
    for (size_t i = 0; i < poses.size(); ++i) {
      const Rigid3 d = LocalRigid(before[i]).Inverse() * LocalRigid(poses[i]);
      move = std::max(move, d.translation.norm());
      turn = std::max(turn, Eigen::AngleAxisd(d.rotation).angle());
    }
    if (move <= kMoveTolerance && turn <= kTurnTolerance) {
      result->converged = true;
      break;
    }
  }
  return FindCorrespondences(o, scans, poses, pairs, s->forest.in);
}

void ReportPairs(const std::vector<PairWork>& pairs, const std::vector<Correspondence>& corr,
                 const Start& s, MultiRegistrationResult* result) {
  std::vector<double> sum(pairs.size(), 0);
  std::vector<int> count(pairs.size(), 0);
  for (const Correspondence& c : corr) {
    const double e = PlaneDistance(c, s.poses);
    sum[c.pair] += e * e;
    ++count[c.pair];
  }
  for (size_t k = 0; k < pairs.size(); ++k) {
    PairReport r = pairs[k].report;
    r.fixed_from_moving = pairs[k].b_from_a;
    if (count[k] > 0) r.rms_global = std::sqrt(sum[k] / count[k]);
    if (r.accepted && s.forest.in[r.moving] && s.forest.in[r.fixed]) {
      const Rigid3 global = LocalRigid(s.poses[r.fixed]).Inverse() * LocalRigid(s.poses[r.moving]);
      const Rigid3 d = pairs[k].b_from_a.Inverse() * global;
      r.discrepancy_translation = d.translation.norm();
      r.discrepancy_rotation_deg = AngleDeg(d.rotation);
    }
    result->pairs.push_back(r);
  }
}

// Per scan figures and the final poses (unconnected scans back at their start); returns how many
// scans are unconnected.
int ReportScans(const std::vector<Correspondence>& corr, const std::vector<Pose>& start, Start* s,
                MultiRegistrationResult* result) {
  const size_t n = start.size();
  std::vector<double> sum(n, 0);
  result->scans.resize(n);
  for (const Correspondence& c : corr) {
    const double e = PlaneDistance(c, s->poses);
    for (int k : {c.src, c.dst}) sum[k] += e * e, ++result->scans[k].correspondences;
  }
  int unconnected = 0;
  for (size_t i = 0; i < n; ++i) {
    ScanReport& r = result->scans[i];
    r.connected = s->forest.in[i];
    if (!r.connected) s->poses[i] = start[i], ++unconnected;
    r.fixed = r.connected && s->held[i];
    const Rigid3 a = LocalRigid(start[i]), b = LocalRigid(s->poses[i]);
    r.translation_change = (b.translation - a.translation).norm();
    r.rotation_change_deg = AngleDeg(b.rotation * a.rotation.conjugate());
    r.residual_rms = r.correspondences > 0 ? std::sqrt(sum[i] / r.correspondences) : kNaN;
    result->world_from_scan.push_back(ToRigid(s->poses[i], result->origin));
  }
  return unconnected;
}

void ReportTargets(const std::vector<ScanTarget>& targets, const Start& s,
                   MultiRegistrationResult* result) {
  for (const ScanTarget& t : targets) {
    result->target_residuals.push_back(
        s.forest.in[t.scan]
            ? Eigen::Vector3d(LocalRigid(s.poses[t.scan]) * t.in_scan - (t.world - result->origin))
            : Eigen::Vector3d::Constant(kNaN));
  }
  FillRmse(result->target_residuals, targets, TargetRole::kControl, &result->control);
  FillRmse(result->target_residuals, targets, TargetRole::kCheck, &result->check);
}

}  // namespace

void MultiRegistrationOptions::Check() const {
  CANDI_CHECK_OPTION(std::isfinite(max_correspondence_distance) && max_correspondence_distance > 0,
                     max_correspondence_distance, "finite and > 0");
  CANDI_CHECK_OPTION(solve_distance > 0 && solve_distance <= max_correspondence_distance,
                     solve_distance, "in (0, max_correspondence_distance]");
  CANDI_CHECK_OPTION_IN(icp_iterations, 1, 100000);
  CANDI_CHECK_OPTION(std::isfinite(voxel) && voxel >= 0, voxel, "finite and >= 0");
  CANDI_CHECK_OPTION(std::isfinite(icp_voxel) && icp_voxel >= 0, icp_voxel, "finite and >= 0");
  CANDI_CHECK_OPTION_IN(pair_rounds, 0, 100);
  CANDI_CHECK_OPTION_IN(min_overlap, 0, 1);
  CANDI_CHECK_OPTION(std::isfinite(loss_scale) && loss_scale > 0, loss_scale, "finite and > 0");
  CANDI_CHECK_OPTION_IN(outer_iterations, 1, 100);
  CANDI_CHECK_OPTION_IN(correspondences_per_pair, 10, 10000000);
  CANDI_CHECK_OPTION_IN(normal_neighbours, 3, 1000);
}

MultiRegistrationResult RegisterScans(const MultiRegistrationOptions& options,
                                      const std::vector<PointCloud>& clouds,
                                      const std::vector<Rigid3>& world_from_scan,
                                      const std::vector<ScanTarget>& targets,
                                      const ProgressCallback& progress) {
  options.Check();
  CheckInput(options, clouds, world_from_scan, targets);
  const int n = static_cast<int>(clouds.size());
  MultiRegistrationResult result;
  Box3d stations;
  for (const Rigid3& p : world_from_scan) stations.Extend(p.translation);
  result.origin = CommonOrigin(stations);

  std::vector<Scan> scans(n);
  ParallelFor(0, n, [&](int i) { scans[i] = PrepareScan(options, clouds[i]); });
  std::vector<Pose> start(n);
  for (int i = 0; i < n; ++i) start[i] = ToPose(world_from_scan[i], result.origin);

  // Candidate pairs: ICP in parallel, each into its own slot; then the robust rounds, serially
  // (the kd-trees are shared between pairs and not safe for concurrent queries).
  std::vector<PairWork> pairs = CandidatePairs(options, scans, start);
  ParallelFor(size_t{0}, pairs.size(),
              [&](size_t k) { RefinePair(options, scans, start, &pairs[k]); });
  for (PairWork& w : pairs) RefinePairRobustly(options, scans, start, &w);
  if (progress) progress(pairs.size(), pairs.size() + options.outer_iterations);

  Start s = StartPoses(options, pairs, targets, start, result.origin);
  const std::vector<Correspondence> corr =
      GlobalRounds(options, scans, pairs, targets, progress, &s, &result);
  ReportPairs(pairs, corr, s, &result);
  const int unconnected = ReportScans(corr, start, &s, &result);
  result.loops = FindLoops(pairs, s.forest);
  ReportTargets(targets, s, &result);
  int accepted = 0;
  for (const PairReport& r : result.pairs) accepted += r.accepted;
  if (result.message.empty()) {
    result.message = std::to_string(n - unconnected) + " of " + std::to_string(n) +
                     " scans registered from " + std::to_string(accepted) + " of " +
                     std::to_string(pairs.size()) + " candidate pairs in " +
                     std::to_string(result.outer_iterations) + " round(s)" +
                     (result.converged ? "" : " (not converged: poses still moving)");
  }
  return result;
}

}  // namespace candi::photogrammetry
