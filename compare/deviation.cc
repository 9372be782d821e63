#include "compare/deviation.h"


#include <tbb/parallel_sort.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "compare/deviation_internal.h"
#include "compare/morton_tree.h"
#include "core/check.h"
#include "core/morton.h"
#include "core/parallel.h"
#include "core/text_format.h"

namespace candi::compare {

namespace internal {

Eigen::Vector3d CommonOrigin(const Box3d& world_box) {
  if (world_box.IsEmpty()) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d c = world_box.Center();
  return Eigen::Vector3d(std::round(c.x()), std::round(c.y()), std::round(c.z()));
}

std::vector<Eigen::Vector3d> RelativePositions(const PointCloud& cloud,
                                               const Eigen::Vector3d& origin) {
  const Eigen::Vector3d delta = cloud.frame.origin - origin;
  std::vector<Eigen::Vector3d> out(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) out[i] = cloud.positions[i] + delta;
  return out;
}

void CheckNotEmpty(size_t size, const std::string& name, const char* what) {
  if (size == 0) throw InputError(name, "", std::string("holds no ") + what + " to compare");
}

void CheckBelowIndexLimit(size_t size, const std::string& name) {
  if (size >= (uint64_t{1} << 32)) {
    throw InputError(name, "", "holds " + std::to_string(size) +
                                   " points; a comparison takes fewer than 2^32 a cloud");
  }
}

std::vector<uint64_t> MortonCodes(const std::vector<Eigen::Vector3d>& points) {
  Box3d box;
  for (const auto& p : points) {
    if (p.allFinite()) box.Extend(p);
  }
  std::vector<uint64_t> codes(points.size());
  const Eigen::Vector3d extent = box.IsEmpty() ? Eigen::Vector3d::Ones() : box.Extent();
  const double scale = ((1u << 21) - 1) / std::max({extent.x(), extent.y(), extent.z(), 1e-300});
  ForEachBlock(0, points.size(), 1 << 16, nullptr, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Eigen::Vector3d& p = points[i];
      uint64_t code = ~uint64_t{0};  // not finite: last
      if (p.allFinite()) {
        const Eigen::Vector3d q = (p - box.min) * scale;
        code = MortonCode21(static_cast<uint64_t>(q.x()), static_cast<uint64_t>(q.y()), static_cast<uint64_t>(q.z()));
      }
      codes[i] = code;
    }
  });
  return codes;
}

std::vector<uint32_t> MortonOrder(const std::vector<Eigen::Vector3d>& points) {
  const std::vector<uint64_t> codes = MortonCodes(points);
  std::vector<std::pair<uint64_t, uint32_t>> keys(points.size());
  ForEachBlock(0, points.size(), 1 << 16, nullptr, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) keys[i] = {codes[i], static_cast<uint32_t>(i)};
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<uint32_t> order(points.size());
  for (size_t i = 0; i < keys.size(); ++i) order[i] = keys[i].second;
  return order;
}

Box3d FiniteWorldBounds(const PointCloud& cloud) {
  Box3d box;
  for (const auto& p : cloud.positions) {
    if (p.allFinite()) box.Extend(p);
  }
  return box.Translated(cloud.frame.origin);
}

double BoxGap(const Box3d& a, const Box3d& b) {
  if (a.IsEmpty() || b.IsEmpty()) return 0.0;
  double sq = 0;
  for (int k = 0; k < 3; ++k) {
    const double g = std::max({0.0, a.min[k] - b.max[k], b.min[k] - a.max[k]});
    sq += g * g;
  }
  return std::sqrt(sq);
}

void Finish(DeviationResult& result, uint64_t not_finite, double gap,
            const std::string& compared_name) {
  result.undefined = 0;
  for (double d : result.distance) result.undefined += std::isnan(d) ? 1 : 0;
  if (not_finite > 0) {
    result.warnings.push_back(compared_name + ": " + std::to_string(not_finite) +
                              " point(s) have a position that is not finite; their distance is NaN");
  }
  if (gap > 0) {
    result.warnings.push_back(compared_name + " lies " + FormatSignificant(gap, 4) +
                              " m from the reference's bounding box: the clouds do not overlap "
                              "(a different frame, CRS or unit?)");
  }
}

}  // namespace internal

namespace {

using internal::MortonTree;
using Points = std::vector<Eigen::Vector3d>;

// The reference's finite points about `origin`, in Morton order (internal::MortonOrder); the
// count left out goes to `dropped`.
Points FinitePoints(const PointCloud& cloud, const Eigen::Vector3d& origin, uint64_t& dropped) {
  const std::vector<Eigen::Vector3d> relative = internal::RelativePositions(cloud, origin);
  Points out;
  out.reserve(cloud.size());
  dropped = 0;
  for (uint32_t i : internal::MortonOrder(relative)) {
    if (relative[i].allFinite()) {
      out.push_back(relative[i]);
    } else {
      ++dropped;
    }
  }
  return out;
}

struct PreparedClouds {
  Eigen::Vector3d origin;
  Points reference;
  std::vector<Eigen::Vector3d> compared;
  uint64_t compared_not_finite = 0;
  double gap = 0;
  std::unique_ptr<MortonTree> tree;
};

PreparedClouds Prepare(const PointCloud& reference, const PointCloud& compared,
                       const std::string& reference_name, const std::string& compared_name,
                       std::vector<std::string>& warnings) {
  internal::CheckNotEmpty(reference.size(), reference_name);
  internal::CheckNotEmpty(compared.size(), compared_name);
  internal::CheckBelowIndexLimit(reference.size(), reference_name);
  internal::CheckBelowIndexLimit(compared.size(), compared_name);
  PreparedClouds p;
  p.origin = internal::CommonOrigin(internal::FiniteWorldBounds(reference));
  uint64_t dropped = 0;
  p.reference = FinitePoints(reference, p.origin, dropped);
  if (p.reference.empty()) {
    throw InputError(reference_name, "", "no point has a finite position");
  }
  if (dropped > 0) {
    warnings.push_back(reference_name + ": " + std::to_string(dropped) +
                       " point(s) with a position that is not finite were left out");
  }
  p.compared = internal::RelativePositions(compared, p.origin);
  for (const auto& q : p.compared) p.compared_not_finite += q.allFinite() ? 0 : 1;
  // A gap small next to the clouds' size is a change (a floor raised 5 cm over 10 m: its flat
  // box does not meet the other's), not clouds apart.
  const Box3d reference_box = internal::FiniteWorldBounds(reference), compared_box = internal::FiniteWorldBounds(compared);
  const double gap = internal::BoxGap(reference_box, compared_box);
  const double size = std::max(reference_box.IsEmpty() ? 0.0 : reference_box.Extent().norm(),
                               compared_box.IsEmpty() ? 0.0 : compared_box.Extent().norm());
  p.gap = gap > 0.1 * size ? gap : 0.0;
  p.tree = std::make_unique<MortonTree>(p.reference);
  return p;
}

// PCA of points given relative to a centre: eigenvalues ascending and their vectors (columns).
struct Pca {
  Eigen::Vector3d mean;
  Eigen::Vector3d values;
  Eigen::Matrix3d vectors;
  // A plane needs two directions of spread: false for coincident or collinear points.
  bool Planar() const { return values[2] > 0 && values[1] > 1e-12 * values[2]; }
};

Pca PcaOf(const std::vector<Eigen::Vector3d>& pts) {
  Pca pca;
  pca.mean.setZero();
  for (const auto& p : pts) pca.mean += p;
  pca.mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d d = p - pca.mean;
    cov.noalias() += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  pca.values = solver.eigenvalues();
  pca.vectors = solver.eigenvectors();
  return pca;
}

// Distance from q to the quadric w = f(u, v) fitted in the PCA frame of `pts`; NaN when the
// fit is singular. First order: |w - f| / sqrt(1 + |grad f|^2).
double QuadricDistance(const Pca& pca, const std::vector<Eigen::Vector3d>& pts,
                       const Eigen::Vector3d& q) {
  const Eigen::Vector3d e_u = pca.vectors.col(2), e_v = pca.vectors.col(1),
                        e_w = pca.vectors.col(0);
  const double scale = std::sqrt(pca.values[2] / static_cast<double>(pts.size()));
  Eigen::MatrixXd a(pts.size(), 6);
  Eigen::VectorXd b(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3d d = (pts[i] - pca.mean) / scale;
    const double u = d.dot(e_u), v = d.dot(e_v);
    a.row(static_cast<Eigen::Index>(i)) << 1, u, v, u * u, u * v, v * v;
    b[static_cast<Eigen::Index>(i)] = d.dot(e_w);
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
  qr.setThreshold(1e-10);
  if (qr.rank() < 6) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd c = qr.solve(b);
  const Eigen::Vector3d d = (q - pca.mean) / scale;
  const double u = d.dot(e_u), v = d.dot(e_v), w = d.dot(e_w);
  const double f = c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v;
  const double fu = c[1] + 2 * c[3] * u + c[4] * v, fv = c[2] + c[4] * u + 2 * c[5] * v;
  return scale * std::abs(w - f) / std::sqrt(1 + fu * fu + fv * fv);
}

DeviationResult CloudToCloud(const DeviationOptions& options, PreparedClouds& p,
                             const ProgressCallback& progress) {
  const C2cOptions& o = options.c2c;
  DeviationResult result;
  result.method = Method::kC2C;
  const size_t n = p.compared.size();
  result.distance.assign(n, std::numeric_limits<double>::quiet_NaN());
  const size_t k = o.local_model == LocalModel::kNone
                       ? 1
                       : std::min<size_t>(static_cast<size_t>(o.model_neighbours),
                                          p.reference.size());
  std::atomic<uint64_t> fallbacks{0};
  const std::vector<uint32_t> order = internal::MortonOrder(p.compared);
  ForEachBlock(options.threads, n, internal::kBlock, progress, [&](size_t begin, size_t end) {
    std::vector<uint32_t> index(k);
    std::vector<double> dist_sq(k);
    std::vector<Eigen::Vector3d> pts;
    uint64_t local_fallbacks = 0;
    int64_t hint = -1;  // the previous query's nearest reference point
    for (size_t j = begin; j < end; ++j) {
      const size_t i = order[j];
      const Eigen::Vector3d& q = p.compared[i];
      if (!q.allFinite()) continue;
      size_t got = 1;
      if (k == 1) {
        // The previous query's nearest point bounds this one's search (the queries go along a
        // Z-order curve, so it is near): the same distance, fewer nodes visited.
        hint = p.tree->Nearest(q, hint);
        index[0] = static_cast<uint32_t>(hint);
      } else {
        got = p.tree->Knn(q, k, index.data(), dist_sq.data());
      }
      double d = (q - p.reference[index[0]]).norm();
      if (o.local_model != LocalModel::kNone && d > 0) {
        pts.clear();
        for (size_t j = 0; j < got; ++j) pts.push_back(p.reference[index[j]]);
        const Pca pca = PcaOf(pts);
        double model = std::numeric_limits<double>::quiet_NaN();
        if (got >= 3 && pca.Planar()) {
          model = o.local_model == LocalModel::kPlane || got < 6
                      ? std::abs(pca.vectors.col(0).dot(q - pca.mean))
                      : QuadricDistance(pca, pts, q);
        }
        if (std::isnan(model)) {
          ++local_fallbacks;
        } else {
          d = std::min(d, model);
        }
      }
      result.distance[i] = d;
    }
    fallbacks += local_fallbacks;
  });
  result.model_fallbacks = fallbacks;
  if (result.model_fallbacks > 0) {
    result.warnings.push_back(std::to_string(result.model_fallbacks) +
                              " point(s) had reference neighbours that define no " +
                              LocalModelName(o.local_model) +
                              " (coincident or collinear points): measured to the nearest point");
  }
  return result;
}

}  // namespace

std::string MethodName(Method method) {
  switch (method) {
    case Method::kC2C: return "c2c";
    case Method::kC2M: return "c2m";
    case Method::kM3C2: return "m3c2";
  }
  return "?";
}

Method ParseMethod(const std::string& name) {
  for (Method m : {Method::kC2C, Method::kC2M, Method::kM3C2}) {
    if (MethodName(m) == name) return m;
  }
  throw std::invalid_argument("method '" + name + "'; must be c2c, c2m or m3c2");
}

std::string LocalModelName(LocalModel model) {
  switch (model) {
    case LocalModel::kNone: return "none";
    case LocalModel::kPlane: return "plane";
    case LocalModel::kQuadric: return "quadric";
  }
  return "?";
}

LocalModel ParseLocalModel(const std::string& name) {
  for (LocalModel m : {LocalModel::kNone, LocalModel::kPlane, LocalModel::kQuadric}) {
    if (LocalModelName(m) == name) return m;
  }
  throw std::invalid_argument("local model '" + name + "'; must be none, plane or quadric");
}

std::string NormalOrientationName(NormalOrientation orientation) {
  switch (orientation) {
    case NormalOrientation::kPlusX: return "+x";
    case NormalOrientation::kMinusX: return "-x";
    case NormalOrientation::kPlusY: return "+y";
    case NormalOrientation::kMinusY: return "-y";
    case NormalOrientation::kPlusZ: return "+z";
    case NormalOrientation::kMinusZ: return "-z";
    case NormalOrientation::kOutward: return "out";
  }
  return "?";
}

NormalOrientation ParseNormalOrientation(const std::string& name) {
  for (NormalOrientation o :
       {NormalOrientation::kPlusX, NormalOrientation::kMinusX, NormalOrientation::kPlusY,
        NormalOrientation::kMinusY, NormalOrientation::kPlusZ, NormalOrientation::kMinusZ,
        NormalOrientation::kOutward}) {
    if (NormalOrientationName(o) == name) return o;
  }
  throw std::invalid_argument("normal orientation '" + name +
                              "'; must be +x, -x, +y, -y, +z, -z or out");
}

void C2cOptions::Check() const {
  CANDI_CHECK_OPTION_IN(model_neighbours, 3, 1000);
  CANDI_CHECK_OPTION(local_model != LocalModel::kQuadric || model_neighbours >= 6,
                     model_neighbours, ">= 6 for a quadric (6 coefficients)");
}

void C2mOptions::Check() const {}

void M3c2Options::Check() const {
  CANDI_CHECK_OPTION(std::isfinite(normal_scale) && normal_scale >= 0, normal_scale,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(std::isfinite(projection_scale) && projection_scale >= 0, projection_scale,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(std::isfinite(max_depth) && max_depth >= 0, max_depth,
                     "finite and >= 0 (0 = the normal scale)");
  CANDI_CHECK_OPTION(std::isfinite(registration_error) && registration_error >= 0,
                     registration_error, "finite and >= 0");
  CANDI_CHECK_OPTION_IN(min_points, 2, 1000000);
}

void DeviationOptions::Check() const {
  c2c.Check();
  c2m.Check();
  m3c2.Check();
  CANDI_CHECK_OPTION_IN(threads, 0, 1024);
}

std::pair<double, double> AutoM3c2Scales(const PointCloud& reference) {
  uint64_t dropped = 0;
  const Points pts =
      FinitePoints(reference, internal::CommonOrigin(internal::FiniteWorldBounds(reference)), dropped);
  if (pts.size() < 2) {
    throw InputError("cannot choose M3C2's scales from fewer than 2 reference points; give "
                     "--normal-scale and --projection-scale");
  }
  const MortonTree tree(pts);
  // The density from the distance r to the 16th neighbour (16 points in pi r^2 of a surface);
  // d so that a cylinder of diameter d holds ~30 reference points.
  constexpr size_t kNeighbours = 16;
  constexpr double kTarget = 30;
  const size_t k = std::min(kNeighbours + 1, pts.size());
  const size_t samples = std::min<size_t>(1000, pts.size());
  std::vector<double> radius;
  std::vector<uint32_t> index(k);
  std::vector<double> dist_sq(k);
  for (size_t s = 0; s < samples; ++s) {
    const size_t i = s * pts.size() / samples;
    const size_t got = tree.Knn(pts[i], k, index.data(), dist_sq.data());
    if (got == k && dist_sq[k - 1] > 0) radius.push_back(std::sqrt(dist_sq[k - 1]));
  }
  if (radius.empty()) {
    throw InputError("cannot choose M3C2's scales: the reference holds too few distinct points; give "
                     "--normal-scale and --projection-scale");
  }
  std::nth_element(radius.begin(), radius.begin() + radius.size() / 2, radius.end());
  const double r = radius[radius.size() / 2];
  const double density = static_cast<double>(k - 1) / (3.14159265358979323846 * r * r);
  const double d = std::sqrt(4 * kTarget / (3.14159265358979323846 * density));
  return {2 * d, d};
}

DeviationResult CompareToCloud(const DeviationOptions& options, const PointCloud& reference,
                               const PointCloud& compared, const std::string& reference_name,
                               const std::string& compared_name,
                               const ProgressCallback& progress) {
  options.Check();
  if (options.method == Method::kC2M) {
    throw std::invalid_argument("DeviationOptions::method = c2m; needs a mesh (CompareToMesh)");
  }
  std::vector<std::string> warnings;
  PreparedClouds p = Prepare(reference, compared, reference_name, compared_name, warnings);
  DeviationResult result;
  if (options.method == Method::kC2C) {
    result = CloudToCloud(options, p, progress);
  } else {
    DeviationOptions resolved = options;
    if (resolved.m3c2.normal_scale == 0 || resolved.m3c2.projection_scale == 0) {
      const auto [big_d, small_d] = AutoM3c2Scales(reference);
      if (resolved.m3c2.normal_scale == 0) resolved.m3c2.normal_scale = big_d;
      if (resolved.m3c2.projection_scale == 0) resolved.m3c2.projection_scale = small_d;
    }
    result = internal::M3c2(resolved, p.reference, *p.tree, p.compared, progress);
  }
  warnings.insert(warnings.end(), result.warnings.begin(), result.warnings.end());
  result.warnings = warnings;
  internal::Finish(result, p.compared_not_finite, p.gap, compared_name);
  return result;
}

namespace {

// Sets the float field `name` of `cloud` to `values` (added, or replaced when present).
template <typename T>
void SetField(PointCloud& cloud, const std::string& name, const std::vector<T>& values) {
  ScalarField* field = cloud.FindScalar(name);
  if (!field) field = &cloud.scalars[static_cast<size_t>(cloud.AddScalarField(name))];
  for (size_t i = 0; i < values.size(); ++i) field->Set(i, static_cast<double>(values[i]));
}

}  // namespace

PointCloud WithDeviationFields(const PointCloud& compared, const DeviationResult& result) {
  CANDI_CHECK(result.distance.size() == compared.size());
  PointCloud out = compared;
  SetField(out, "distance", result.distance);
  if (result.method == Method::kM3C2) {
    SetField(out, "lod95", result.lod95);
    SetField(out, "significant", result.significant);
    SetField(out, "n_reference", result.reference_count);
    SetField(out, "n_compared", result.compared_count);
    SetField(out, "std_reference", result.reference_std);
    SetField(out, "std_compared", result.compared_std);
    PointSchema schema = out.schema;
    schema.normals = true;
    out.SetSchema(schema);
    out.normals = result.normals;
  }
  out.CheckConsistent();
  return out;
}

}  // namespace candi::compare
