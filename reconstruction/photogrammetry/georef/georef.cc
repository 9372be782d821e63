#include "reconstruction/photogrammetry/georef/georef.h"

#include <ceres/ceres.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>
#include <stdexcept>

#include "core/box.h"
#include "core/check.h"
#include "io/csv_table.h"

namespace candi::photogrammetry {

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

SurveyTarget ParseTarget(const io::CsvTable& t, const io::CsvTable::Row& row, bool model_columns) {
  SurveyTarget target;
  target.line = row.line;
  target.name = t.Text(row, "name");
  if (target.name.empty()) t.Fail(row, "name", "empty");
  target.survey = Eigen::Vector3d(t.Number(row, "E"), t.Number(row, "N"), t.Number(row, "H"));
  const std::string role = Lower(t.Text(row, "role"));
  if (role == "control") {
    target.role = TargetRole::kControl;
  } else if (role == "check") {
    target.role = TargetRole::kCheck;
  } else {
    t.Fail(row, "role", "'" + t.Text(row, "role") + "'; must be control or check");
  }
  target.accuracy = t.Number(row, "accuracy");
  if (!(target.accuracy > 0)) t.Fail(row, "accuracy", t.Text(row, "accuracy") + "; must be > 0 m");
  if (!model_columns) return target;
  const int empty = t.Text(row, "x").empty() + t.Text(row, "y").empty() + t.Text(row, "z").empty();
  if (empty == 3) return target;  // picked in images instead
  target.model = Eigen::Vector3d(t.Number(row, "x"), t.Number(row, "y"), t.Number(row, "z"));
  target.has_model = true;
  return target;
}

struct Reprojection {
  ProjectionMatrix p;
  Eigen::Vector2d uv;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    T h[3];
    for (int i = 0; i < 3; ++i) {
      h[i] = T(p(i, 0)) * x[0] + T(p(i, 1)) * x[1] + T(p(i, 2)) * x[2] + T(p(i, 3));
    }
    r[0] = h[0] / h[2] - T(uv[0]);
    r[1] = h[1] / h[2] - T(uv[1]);
    return true;
  }
};

Eigen::Vector2d Project(const ProjectionMatrix& p, const Eigen::Vector3d& x) {
  return (p * x.homogeneous()).hnormalized();
}

// Depth sign of x in camera p (positive: in front), Hartley & Zisserman eq. 6.15.
bool InFront(const ProjectionMatrix& p, const Eigen::Vector3d& x) {
  return (p * x.homogeneous())[2] * p.leftCols<3>().determinant() > 0;
}

Eigen::Vector3d LinearTriangulation(const std::vector<ProjectionMatrix>& cameras,
                                    const std::vector<Eigen::Vector2d>& uv) {
  Eigen::MatrixXd a(2 * cameras.size(), 4);
  for (size_t k = 0; k < cameras.size(); ++k) {
    const auto& p = cameras[k];
    Eigen::RowVector4d r0 = uv[k].x() * p.row(2) - p.row(0);
    Eigen::RowVector4d r1 = uv[k].y() * p.row(2) - p.row(1);
    a.row(static_cast<Eigen::Index>(2 * k)) = r0 / std::max(r0.norm(), 1e-300);
    a.row(static_cast<Eigen::Index>(2 * k + 1)) = r1 / std::max(r1.norm(), 1e-300);
  }
  const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::MatrixXd>(a, Eigen::ComputeFullV).matrixV().col(3);
  return h.hnormalized();
}

void Accumulate(const Eigen::Vector3d& d, Rmse* r) {
  ++r->count;
  r->x += d.x() * d.x();
  r->y += d.y() * d.y();
  r->z += d.z() * d.z();
}

void Finish(Rmse* r) {
  if (r->count == 0) return;
  r->xy = std::sqrt((r->x + r->y) / r->count);
  r->d3 = std::sqrt((r->x + r->y + r->z) / r->count);
  r->x = std::sqrt(r->x / r->count);
  r->y = std::sqrt(r->y / r->count);
  r->z = std::sqrt(r->z / r->count);
}

}  // namespace

Rmse RmseOf(const std::vector<Eigen::Vector3d>& residuals) {
  Rmse r;
  for (const Eigen::Vector3d& d : residuals) Accumulate(d, &r);
  Finish(&r);
  return r;
}

std::string TargetRoleName(TargetRole role) {
  return role == TargetRole::kControl ? "control" : "check";
}

std::vector<SurveyTarget> ReadSurveyTargets(const std::string& path) {
  const io::CsvTable t = io::CsvTable::Read(path, {"name", "E", "N", "H", "role", "accuracy"});
  const int model_columns = t.Has("x") + t.Has("y") + t.Has("z");
  if (model_columns != 0 && model_columns != 3) {
    throw InputError(path, "line 1", "the model columns must be x, y and z together");
  }
  std::vector<SurveyTarget> targets;
  std::set<std::string> names;
  for (const io::CsvTable::Row& row : t.rows()) {
    targets.push_back(ParseTarget(t, row, model_columns == 3));
    if (!names.insert(targets.back().name).second) {
      t.Fail(row, "name", "'" + targets.back().name + "' appears twice");
    }
  }
  if (targets.empty()) throw InputError(path, "", "no targets (only a header)");
  return targets;
}

std::vector<ImagePick> ReadImagePicks(const std::string& path) {
  const io::CsvTable t = io::CsvTable::Read(path, {"name", "image", "u", "v"});
  std::vector<ImagePick> picks;
  for (const io::CsvTable::Row& row : t.rows()) {
    ImagePick p;
    p.line = row.line;
    p.target = t.Text(row, "name");
    p.image = t.Text(row, "image");
    if (p.image.empty()) t.Fail(row, "image", "empty");
    p.uv = Eigen::Vector2d(t.Number(row, "u"), t.Number(row, "v"));
    picks.push_back(p);
  }
  return picks;
}

Triangulation TriangulatePoint(const std::vector<ProjectionMatrix>& cameras,
                               const std::vector<Eigen::Vector2d>& uv) {
  if (cameras.size() < 2 || cameras.size() != uv.size()) {
    throw std::invalid_argument("TriangulatePoint: " + std::to_string(cameras.size()) +
                                " cameras and " + std::to_string(uv.size()) +
                                " observations; need >= 2 of each, equal in number");
  }
  Triangulation t;
  Eigen::Vector3d x = LinearTriangulation(cameras, uv);
  if (x.allFinite()) {
    ceres::Problem problem;
    for (size_t k = 0; k < cameras.size(); ++k) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Reprojection, 2, 3>(
                                   new Reprojection{cameras[k], uv[k]}),
                               nullptr, x.data());
    }
    ceres::Solver::Options options;
    options.linear_solver_type = ceres::DENSE_QR;
    options.logging_type = ceres::SILENT;
    options.num_threads = 1;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    t.converged = summary.termination_type == ceres::CONVERGENCE;
  }
  t.point = x;
  double sum = 0;
  for (size_t k = 0; k < cameras.size(); ++k) {
    const double e = (Project(cameras[k], x) - uv[k]).norm();
    sum += e * e;
    t.max_px = std::max(t.max_px, e);
    t.in_front = t.in_front && InFront(cameras[k], x);
  }
  t.rms_px = std::sqrt(sum / static_cast<double>(cameras.size()));
  if (!x.allFinite()) t.in_front = false;
  return t;
}

int TriangulateTargets(const std::vector<ImagePick>& picks, const std::string& picks_path,
                       const std::map<std::string, ProjectionMatrix>& cameras,
                       std::vector<SurveyTarget>* targets) {
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < targets->size(); ++i) index[(*targets)[i].name] = i;
  std::map<size_t, std::pair<std::vector<ProjectionMatrix>, std::vector<Eigen::Vector2d>>> views;
  int skipped = 0;
  for (const ImagePick& p : picks) {
    const auto it = index.find(p.target);
    if (it == index.end()) {
      throw InputError(picks_path, "line " + std::to_string(p.line),
                       "field 'name': '" + p.target + "' is not in the targets file");
    }
    const auto camera = cameras.find(p.image);
    if (camera == cameras.end()) {
      ++skipped;
      continue;
    }
    views[it->second].first.push_back(camera->second);
    views[it->second].second.push_back(p.uv);
  }
  for (size_t i = 0; i < targets->size(); ++i) {
    SurveyTarget& target = (*targets)[i];
    if (target.has_model) continue;
    const auto it = views.find(i);
    const size_t n = it == views.end() ? 0 : it->second.first.size();
    if (n < 2) {
      target.unused_reason = "picked in " + std::to_string(n) + " image(s) of the model; needs 2";
      continue;
    }
    const Triangulation t = TriangulatePoint(it->second.first, it->second.second);
    target.views = static_cast<int>(n);
    target.reprojection_px = t.rms_px;
    if (!t.in_front) {
      target.unused_reason = "triangulated behind a camera (check the picks)";
      continue;
    }
    target.model = t.point;
    target.has_model = true;
  }
  return skipped;
}

GeorefResult Georeference(const SimilarityFitOptions& options,
                          const std::vector<SurveyTarget>& targets,
                          const std::string& targets_path) {
  GeorefResult r;
  r.targets = targets;
  std::vector<Eigen::Vector3d> model, survey;
  std::vector<double> accuracy;
  std::vector<size_t> fitted;  // target index of each fit correspondence
  Box3d box;
  for (size_t i = 0; i < targets.size(); ++i) {
    SurveyTarget& t = r.targets[i];
    box.Extend(t.survey);
    if (!t.has_model && t.unused_reason.empty()) t.unused_reason = "no model coordinates or picks";
    if (t.role != TargetRole::kControl || !t.has_model) continue;
    model.push_back(t.model);
    survey.push_back(t.survey);
    accuracy.push_back(t.accuracy);
    fitted.push_back(i);
  }
  if (model.size() < 3) {
    throw InputError(targets_path, "", std::to_string(model.size()) +
                                           " usable control targets; a similarity needs at "
                                           "least 3 (give model coordinates or picks)");
  }
  r.fit = FitSimilarity(options, model, survey, accuracy);
  r.survey_from_model = r.fit.target_from_source;
  r.frame = LocalFrame::Auto(box);
  r.residuals.assign(targets.size(), Eigen::Vector3d::Zero());
  r.outlier.assign(targets.size(), false);
  for (size_t k = 0; k < fitted.size(); ++k) {
    r.residuals[fitted[k]] = r.fit.residuals[k];
    r.outlier[fitted[k]] = r.fit.outlier[k];
    if (!r.fit.outlier[k]) Accumulate(r.fit.residuals[k], &r.control);
  }
  for (size_t i = 0; i < targets.size(); ++i) {
    const SurveyTarget& t = r.targets[i];
    if (t.role != TargetRole::kCheck || !t.has_model) continue;
    // Both terms are ~10^6 m; their difference keeps ~1e-9 m in double.
    r.residuals[i] = r.survey_from_model * t.model - t.survey;
    r.outlier[i] = r.residuals[i].norm() > r.fit.threshold;
    Accumulate(r.residuals[i], &r.check);
  }
  Finish(&r.control);
  Finish(&r.check);
  return r;
}

void ApplySimilarity(const Sim3& survey_from_model, const LocalFrame& out, PointCloud* cloud) {
  const Eigen::Matrix3d sr = survey_from_model.scale * survey_from_model.rotation.toRotationMatrix();
  const Eigen::Vector3d offset = sr * cloud->frame.origin + survey_from_model.translation - out.origin;
  for (Eigen::Vector3d& p : cloud->positions) p = sr * p + offset;
  if (cloud->schema.normals) {
    const Eigen::Matrix3f r = survey_from_model.rotation.toRotationMatrix().cast<float>();
    for (Eigen::Vector3f& n : cloud->normals) n = (r * n).normalized();
  }
  cloud->frame = out;
}

}  // namespace candi::photogrammetry
