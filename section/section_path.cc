#include "section/section_path.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>

namespace candi::section {

namespace {

void CheckThickness(double thickness) {
  if (!(std::isfinite(thickness) && thickness > 0)) {
    char text[64];
    std::snprintf(text, sizeof(text), "%g", thickness);
    throw std::invalid_argument(std::string("--thickness ") + text + ": must be a finite number > 0 (metres)");
  }
}

// The shortest of %.15g and %.17g that reads back as v.
std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.15g", v);
  if (std::strtod(text, nullptr) != v) std::snprintf(text, sizeof(text), "%.17g", v);
  return text;
}

std::string Vec(const Eigen::Vector3d& v) { return "[" + Num(v.x()) + ", " + Num(v.y()) + ", " + Num(v.z()) + "]"; }

// Distance in plan from x to the segment [a, b].
double PlanDistance(const Eigen::Vector2d& x, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double t = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (x - (a + t * d)).norm();
}

}  // namespace

void SectionPath::AddSegment(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double chainage0,
                             double length) {
  const Eigen::Vector3d n = normal.normalized();
  Eigen::Vector3d u, v;
  if (std::abs(n.z()) > 1 - 1e-12) {
    horizontal_ = true;
    u = Eigen::Vector3d::UnitX();
    v = Eigen::Vector3d::UnitY();
  } else {
    u = n.cross(Eigen::Vector3d::UnitZ()).normalized();
    v = u.cross(n);
  }
  p_.push_back(point);
  n_.push_back(n);
  u_.push_back(u);
  v_.push_back(v);
  chainage_.push_back(chainage0);
  length_.push_back(length);
  ClipRegion slab = ClipRegion::Slab(point, n, thickness_);
  if (std::isfinite(length)) {  // a path's segment ends half a thickness beyond its vertices
    slab.planes.push_back({point - 0.5 * thickness_ * u, u});
    slab.planes.push_back({point + (length + 0.5 * thickness_) * u, -u});
  }
  regions_.push_back(std::move(slab));
}

SectionPath SectionPath::Plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double thickness) {
  CheckThickness(thickness);
  if (!point.allFinite()) throw std::invalid_argument("--plane: the point is not finite");
  if (!normal.allFinite() || !(normal.norm() > 0)) throw std::invalid_argument("--plane: the normal is zero or not finite");
  SectionPath s;
  s.thickness_ = thickness;
  s.AddSegment(point, normal, 0, std::numeric_limits<double>::infinity());
  return s;
}

SectionPath SectionPath::Through(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double thickness) {
  CheckThickness(thickness);
  if (!a.allFinite() || !b.allFinite()) throw std::invalid_argument("--through: a point is not finite");
  Eigen::Vector3d d = b - a;
  d.z() = 0;
  if (!(d.norm() > 1e-9)) {
    throw std::invalid_argument("--through: the two points coincide in plan; a vertical plane needs two distinct "
                                "points (use --plane for a horizontal cut)");
  }
  return Plane(a, Eigen::Vector3d::UnitZ().cross(d.normalized()), thickness);
}

SectionPath SectionPath::Path(const std::vector<Eigen::Vector2d>& plan, double thickness, size_t* merged) {
  CheckThickness(thickness);
  std::vector<Eigen::Vector2d> v;
  for (const Eigen::Vector2d& p : plan) {
    if (!p.allFinite()) throw std::invalid_argument("--path: a vertex is not finite");
    if (!v.empty() && (p - v.back()).norm() <= 1e-9) continue;
    v.push_back(p);
  }
  if (merged) *merged = plan.size() - v.size();
  if (v.size() < 2) {
    throw std::invalid_argument("--path: " + std::to_string(plan.size()) + " vertices, " + std::to_string(v.size()) +
                                " distinct: a path needs two distinct vertices at least");
  }
  SectionPath s;
  s.thickness_ = thickness;
  s.path_ = v;
  double chainage = 0;
  for (size_t i = 0; i + 1 < v.size(); ++i) {
    const Eigen::Vector2d d = v[i + 1] - v[i];
    const Eigen::Vector3d dir(d.x() / d.norm(), d.y() / d.norm(), 0);
    s.AddSegment(Eigen::Vector3d(v[i].x(), v[i].y(), 0), Eigen::Vector3d::UnitZ().cross(dir), chainage, d.norm());
    chainage += d.norm();
  }
  return s;
}

Eigen::Vector2d SectionPath::ToDrawing(const Eigen::Vector3d& world, size_t segment, double* depth) const {
  const Eigen::Vector3d r = world - p_[segment];
  if (depth) *depth = r.dot(n_[segment]);
  if (horizontal_) return {world.x(), world.y()};
  return {chainage_[segment] + r.dot(u_[segment]), r.dot(v_[segment]) + p_[segment].z()};
}

size_t SectionPath::NearestSegment(const Eigen::Vector3d& world) const {
  if (path_.empty()) return 0;
  size_t best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < path_.size(); ++i) {
    const double d = PlanDistance(world.head<2>(), path_[i], path_[i + 1]);
    if (d < best_d) best_d = d, best = i;
  }
  return best;
}

Eigen::Vector3d SectionPath::ToWorld(const Eigen::Vector2d& drawing) const {
  if (horizontal_) {
    const Eigen::Vector3d& p = p_[0];
    const Eigen::Vector3d& n = n_[0];
    return {drawing.x(), drawing.y(), p.z() - (n.x() * (drawing.x() - p.x()) + n.y() * (drawing.y() - p.y())) / n.z()};
  }
  size_t s = 0;
  while (s + 1 < chainage_.size() && drawing.x() > chainage_[s] + length_[s]) ++s;
  return p_[s] + u_[s] * (drawing.x() - chainage_[s]) + v_[s] * (drawing.y() - p_[s].z());
}

std::string SectionPath::Describe() const {
  const std::string t = Num(thickness_) + " m thick";
  if (!path_.empty()) {
    return "path of " + std::to_string(path_.size()) + " vertices, " + Num(chainage_.back() + length_.back()) +
           " m long, " + t;
  }
  return "plane through " + Vec(p_[0]) + " normal " + Vec(n_[0]) + ", " + t;
}

std::string SectionPath::ToJson() const {
  std::string out = "{\"thickness\": " + Num(thickness_);
  if (!path_.empty()) {
    out += ", \"kind\": \"path\", \"vertices\": [";
    for (size_t i = 0; i < path_.size(); ++i) {
      out += (i ? ", [" : "[") + Num(path_[i].x()) + ", " + Num(path_[i].y()) + "]";
    }
    out += "], \"length\": " + Num(chainage_.back() + length_.back());
  } else {
    out += std::string(", \"kind\": \"") + (horizontal_ ? "plan" : "plane") + "\", \"point\": " + Vec(p_[0]) +
           ", \"normal\": " + Vec(n_[0]) + ", \"u\": " + Vec(u_[0]) + ", \"v\": " + Vec(v_[0]);
  }
  return out + "}";
}

}  // namespace candi::section
