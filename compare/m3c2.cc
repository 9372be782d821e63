// M3C2 (Lague, Brodu & Leroux 2013, ISPRS J. 82: "Accurate 3D comparison of complex topography
// with terrestrial laser scanner"), with the compared cloud's points as core points.
#include <Eigen/Eigenvalues>
#include <atomic>
#include <cmath>
#include <limits>

#include "compare/deviation_internal.h"
#include "compare/morton_tree.h"
#include "core/check.h"
#include "core/parallel.h"
#include "core/text_format.h"

namespace candi::compare::internal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Points along the axis: count, mean and sample standard deviation of their positions t.
struct AxisStats {
  uint32_t n = 0;
  double sum = 0, sum_sq = 0;
  void Add(double t) {
    ++n;
    sum += t;
    sum_sq += t * t;
  }
  double Mean() const { return sum / n; }
  double Std() const {
    if (n < 2) return kNaN;
    const double var = (sum_sq - sum * Mean()) / (n - 1);
    return std::sqrt(std::max(0.0, var));
  }
};

// The points of `tree` in the cylinder through q along unit n: radius r, half-length h.
AxisStats InCylinder(const MortonTree& tree, const Eigen::Vector3d& q, const Eigen::Vector3d& n,
                     double r, double h) {
  AxisStats stats;
  const double r_sq = r * r;
  tree.ForEachWithin(q, std::sqrt(r_sq + h * h), [&](uint32_t index, double dist_sq) {
    const double t = n.dot(tree.point(index) - q);
    if (std::abs(t) <= h && dist_sq - t * t <= r_sq) stats.Add(t);
  });
  return stats;
}

// The normal at q from the reference points within `radius`: PCA's smallest direction; NaN
// when fewer than 3 points or they define no plane (coincident or collinear).
Eigen::Vector3d NormalAt(const MortonTree& tree, const Eigen::Vector3d& q, double radius) {
  size_t count = 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  tree.ForEachWithin(q, radius, [&](uint32_t index, double) {
    const Eigen::Vector3d d = tree.point(index) - q;  // about q: small numbers, no cancellation
    ++count;
    sum += d;
    outer.noalias() += d * d.transpose();
  });
  if (count < 3) return Eigen::Vector3d::Constant(kNaN);
  const Eigen::Vector3d mean = sum / static_cast<double>(count);
  const Eigen::Matrix3d cov = outer / static_cast<double>(count) - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  const Eigen::Vector3d values = solver.eigenvalues();
  if (!(values[2] > 0 && values[1] > 1e-10 * values[2])) return Eigen::Vector3d::Constant(kNaN);
  return solver.eigenvectors().col(0).normalized();
}

// Flips n to the stated side; for an axis, a normal perpendicular to it goes by the next axis.
Eigen::Vector3d Oriented(Eigen::Vector3d n, NormalOrientation o, const Eigen::Vector3d& q,
                         const Eigen::Vector3d& centroid) {
  double side = 0;
  auto axis_side = [&](int axis, double sign) {
    for (int k = 0; k < 3; ++k) {
      const double c = n[(axis + k) % 3];
      if (std::abs(c) > 1e-9) return sign * c;
    }
    return 1.0;
  };
  switch (o) {
    case NormalOrientation::kPlusX: side = axis_side(0, 1); break;
    case NormalOrientation::kMinusX: side = axis_side(0, -1); break;
    case NormalOrientation::kPlusY: side = axis_side(1, 1); break;
    case NormalOrientation::kMinusY: side = axis_side(1, -1); break;
    case NormalOrientation::kPlusZ: side = axis_side(2, 1); break;
    case NormalOrientation::kMinusZ: side = axis_side(2, -1); break;
    case NormalOrientation::kOutward: side = n.dot(q - centroid); break;
  }
  return side < 0 ? Eigen::Vector3d(-n) : n;
}

}  // namespace

DeviationResult M3c2(const DeviationOptions& options, const std::vector<Eigen::Vector3d>& reference,
                     const MortonTree& reference_tree, const std::vector<Eigen::Vector3d>& compared,
                     const ProgressCallback& progress) {
  const M3c2Options& o = options.m3c2;
  DeviationResult result;
  result.method = Method::kM3C2;
  result.normal_scale = o.normal_scale;
  result.projection_scale = o.projection_scale;
  result.max_depth = o.max_depth > 0 ? o.max_depth : o.normal_scale;
  const double r = 0.5 * o.projection_scale, h = result.max_depth;

  // Core points in Morton order, and the compared cloud's tree over its finite points in it.
  const std::vector<uint32_t> order = MortonOrder(compared);
  std::vector<Eigen::Vector3d> finite;
  finite.reserve(compared.size());
  for (uint32_t i : order) {
    if (compared[i].allFinite()) finite.push_back(compared[i]);
  }
  if (finite.empty()) {
    throw InputError("M3C2: no compared point has a finite position");
  }
  const MortonTree compared_tree(finite);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : reference) centroid += p;
  centroid /= static_cast<double>(reference.size());

  const size_t n = compared.size();
  result.distance.assign(n, kNaN);
  result.lod95.assign(n, kNaN);
  result.significant.assign(n, 0);
  result.normals.assign(n, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  result.reference_count.assign(n, 0);
  result.compared_count.assign(n, 0);
  result.reference_std.assign(n, kNaN);
  result.compared_std.assign(n, kNaN);
  std::atomic<uint64_t> no_normal{0}, too_few{0};
  ForEachBlock(options.threads, n, kBlock, progress, [&](size_t begin, size_t end) {
    uint64_t local_no_normal = 0, local_too_few = 0;
    for (size_t j = begin; j < end; ++j) {
      const size_t i = order[j];
      const Eigen::Vector3d& q = compared[i];
      if (!q.allFinite()) continue;
      Eigen::Vector3d normal = NormalAt(reference_tree, q, 0.5 * o.normal_scale);
      if (!normal.allFinite()) {
        ++local_no_normal;
        continue;
      }
      normal = Oriented(normal, o.orientation, q, centroid);
      result.normals[i] = normal.cast<float>();
      const AxisStats s1 = InCylinder(reference_tree, q, normal, r, h);
      const AxisStats s2 = InCylinder(compared_tree, q, normal, r, h);
      result.reference_count[i] = s1.n;
      result.compared_count[i] = s2.n;
      result.reference_std[i] = s1.Std();
      result.compared_std[i] = s2.Std();
      if (s1.n < static_cast<uint32_t>(o.min_points) || s2.n < static_cast<uint32_t>(o.min_points)) {
        ++local_too_few;
        continue;
      }
      const double d = s2.Mean() - s1.Mean();
      const double sd1 = s1.Std(), sd2 = s2.Std();
      const double lod =
          1.96 * (std::sqrt(sd1 * sd1 / s1.n + sd2 * sd2 / s2.n) + o.registration_error);
      result.distance[i] = d;
      result.lod95[i] = lod;
      result.significant[i] = std::abs(d) > lod ? 1 : 0;
    }
    no_normal += local_no_normal;
    too_few += local_too_few;
  });
  result.no_normal = no_normal;
  result.too_few_points = too_few;
  if (result.no_normal > 0) {
    result.warnings.push_back(
        std::to_string(result.no_normal) + " core point(s) have reference points within D/2 = " +
        FormatSignificant(0.5 * o.normal_scale, 4) +
        " m that define no plane (fewer than 3, coincident or collinear): distance NaN");
  }
  if (result.too_few_points > 0) {
    result.warnings.push_back(std::to_string(result.too_few_points) +
                              " core point(s) have fewer than " + std::to_string(o.min_points) +
                              " points of a cloud in the cylinder (d = " +
                              FormatSignificant(o.projection_scale, 4) + " m, depth +-" +
                              FormatSignificant(h, 4) + " m): distance NaN");
  }
  return result;
}

}  // namespace candi::compare::internal
