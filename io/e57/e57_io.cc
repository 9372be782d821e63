// E57 point reader: the scans of /data3D, one after the other, posed into the file's frame.
#include "io/e57/e57_io.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"
#include "core/log.h"
#include "io/e57/e57_format.h"

namespace candi::io {

namespace {

using e57::FieldDesc;
using e57::FieldKind;
using e57::ScanDesc;

constexpr size_t kBatch = 1 << 14;  // records decoded at a time (columns stay in L2)
constexpr size_t kMaxQueued = size_t{256} << 20;
const Rgb8 kDefaultColor{128, 128, 128};

// Which prototype fields a scan's points come from, and how to convert them.
struct ScanPlan {
  int pos[3] = {-1, -1, -1};  // cartesianX/Y/Z or sphericalRange/Azimuth/Elevation
  bool spherical = false;
  int invalid = -1;            // cartesianInvalidState / sphericalInvalidState
  int rgb[3] = {-1, -1, -1}, color_invalid = -1;
  double color_min[3] = {0, 0, 0}, color_range[3] = {255, 255, 255};  // max - min; 0: flat
  int intensity = -1, intensity_invalid = -1;
  int time = -1, time_invalid = -1;
  bool identity = true;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::vector<bool> wanted;
};

std::string CodingName(const FieldDesc& f) {
  switch (f.kind) {
    case FieldKind::kInteger: return "integer";
    case FieldKind::kScaledInteger: return "scaled integer";
    case FieldKind::kFloat: return "float";
    case FieldKind::kDouble: return "double";
  }
  return "?";
}

class E57Reader : public PointReader {
 public:
  // only_scan >= 0: that scan alone, in its own frame (its pose not applied).
  E57Reader(const std::string& path, const PointReadOptions& options, int only_scan = -1);
  size_t Read(size_t max_points, PointCloud* chunk) override;

 private:
  ScanPlan PlanScan(const ScanDesc& scan) const;
  void SetColorScale(const ScanDesc& scan, ScanPlan* plan) const;
  void BuildInfo();
  bool NextScan();
  size_t Convert(size_t n, size_t at, PointCloud* chunk) const;
  void ConvertPositions(size_t n, std::vector<Eigen::Vector3d>* out) const;

  e57::PagedReader file_;
  bool scalar_fields_ = true;
  e57::FileDesc desc_;
  std::vector<ScanPlan> plans_;
  int intensity_scalar_ = -1, time_scalar_ = -1;
  size_t scan_ = 0;  // index of the scan being read (+1 once opened)
  std::unique_ptr<e57::SectionReader> section_;
  std::vector<std::vector<double>> columns_;
  std::vector<Eigen::Vector3d> positions_;
};

E57Reader::E57Reader(const std::string& path, const PointReadOptions& options, int only_scan)
    : PointReader(path), file_(path), scalar_fields_(options.scalar_fields) {
  desc_ = e57::ParseE57Xml(path, file_.ReadXml(), file_.header().physical_length);
  if (only_scan >= 0) {
    if (static_cast<size_t>(only_scan) >= desc_.scans.size()) {
      throw InputError(path, "", "has " + std::to_string(desc_.scans.size()) + " scan(s); there is no scan " +
                                     std::to_string(only_scan));
    }
    ScanDesc scan = desc_.scans[static_cast<size_t>(only_scan)];
    scan.rotation = Eigen::Quaterniond::Identity();  // its own frame
    scan.translation.setZero();
    desc_.scans = {scan};
  }
  for (const ScanDesc& scan : desc_.scans) plans_.push_back(PlanScan(scan));
  BuildInfo();
  if (desc_.images > 0) {
    LogInfo(path + ": " + std::to_string(desc_.images) + " images2D entries are not read");
  }
}

ScanPlan E57Reader::PlanScan(const ScanDesc& scan) const {
  ScanPlan plan;
  const char* cartesian[3] = {"cartesianX", "cartesianY", "cartesianZ"};
  const char* spherical[3] = {"sphericalRange", "sphericalAzimuth", "sphericalElevation"};
  for (int k = 0; k < 3; ++k) plan.pos[k] = scan.FieldIndex(cartesian[k]);
  if (plan.pos[0] < 0 || plan.pos[1] < 0 || plan.pos[2] < 0) {
    for (int k = 0; k < 3; ++k) plan.pos[k] = scan.FieldIndex(spherical[k]);
    plan.spherical = true;
    if (plan.pos[0] < 0 || plan.pos[1] < 0 || plan.pos[2] < 0) {
      throw InputError(path_, "XML line " + std::to_string(scan.line) + ", " + scan.element +
                                  "/points/prototype",
                       "has neither cartesianX/Y/Z nor sphericalRange/Azimuth/Elevation");
    }
  }
  plan.invalid = scan.FieldIndex(plan.spherical ? "sphericalInvalidState" : "cartesianInvalidState");
  const char* colors[3] = {"colorRed", "colorGreen", "colorBlue"};
  for (int k = 0; k < 3; ++k) plan.rgb[k] = scan.FieldIndex(colors[k]);
  if (plan.rgb[0] >= 0 && plan.rgb[1] >= 0 && plan.rgb[2] >= 0) {
    plan.color_invalid = scan.FieldIndex("isColorInvalid");
    SetColorScale(scan, &plan);
  } else {
    plan.rgb[0] = plan.rgb[1] = plan.rgb[2] = -1;
  }
  if (scalar_fields_) {
    plan.intensity = scan.FieldIndex("intensity");
    plan.intensity_invalid = plan.intensity >= 0 ? scan.FieldIndex("isIntensityInvalid") : -1;
    plan.time = scan.FieldIndex("timeStamp");
    plan.time_invalid = plan.time >= 0 ? scan.FieldIndex("isTimeStampInvalid") : -1;
  }
  plan.rotation = scan.rotation.toRotationMatrix();
  plan.translation = scan.translation;
  plan.identity = plan.rotation == Eigen::Matrix3d::Identity() && plan.translation.isZero(0.0);
  plan.wanted.assign(scan.fields.size(), false);
  for (int f : {plan.pos[0], plan.pos[1], plan.pos[2], plan.invalid, plan.rgb[0], plan.rgb[1],
                plan.rgb[2], plan.color_invalid, plan.intensity, plan.intensity_invalid, plan.time,
                plan.time_invalid}) {
    if (f >= 0) plan.wanted[f] = true;
  }
  return plan;
}

// 8-bit colour = (value - min) * 255 / (max - min): limits from colorLimits, else the fields'.
void E57Reader::SetColorScale(const ScanDesc& scan, ScanPlan* plan) const {
  for (int k = 0; k < 3; ++k) {
    const FieldDesc& f = scan.fields[plan->rgb[k]];
    double lo = 0.0, hi = 255.0;
    if (scan.color_limits[k]) {
      lo = scan.color_limits[k]->x(), hi = scan.color_limits[k]->y();
    } else if (f.kind == FieldKind::kInteger || f.kind == FieldKind::kScaledInteger) {
      lo = static_cast<double>(f.minimum) * f.scale + f.offset;
      hi = static_cast<double>(f.maximum) * f.scale + f.offset;
    }
    plan->color_min[k] = lo;
    plan->color_range[k] = hi > lo ? hi - lo : 0.0;
  }
}

void E57Reader::BuildInfo() {
  info_.format = PointFormat::kE57;
  PointSchema& schema = info_.schema;
  schema.position_type = ScalarType::kFloat64;
  bool unknown = false;
  uint64_t records = 0;
  std::string codings;
  for (size_t i = 0; i < desc_.scans.size(); ++i) {
    const ScanDesc& scan = desc_.scans[i];
    const ScanPlan& plan = plans_[i];
    schema.colors |= plan.rgb[0] >= 0;
    if (plan.intensity >= 0) intensity_scalar_ = 0;
    if (plan.time >= 0) time_scalar_ = 0;
    unknown |= plan.invalid >= 0;
    records += scan.record_count;
    if (i < 4) {
      codings += (i ? ", " : "") + std::string(plan.spherical ? "spherical " : "cartesian ") +
                 CodingName(scan.fields[plan.pos[0]]);
    } else if (i == 4) {
      codings += ", ...";
    }
    const std::string& name = !scan.name.empty() ? scan.name : scan.guid;
    info_.meta.comments.push_back("e57 scan " + std::to_string(i) + ": " + name);
  }
  if (intensity_scalar_ >= 0) {
    intensity_scalar_ = static_cast<int>(schema.scalars.size());
    schema.scalars.push_back({"intensity", ScalarType::kFloat32});
  }
  if (time_scalar_ >= 0) {
    time_scalar_ = static_cast<int>(schema.scalars.size());
    schema.scalars.push_back({"time_stamp", ScalarType::kFloat64});
  }
  info_.count = unknown ? kUnknownCount : records;
  info_.meta.crs = desc_.coordinate_metadata;
  const size_t n = desc_.scans.size();
  info_.description = "E57 " + std::to_string(desc_.major) + "." + std::to_string(desc_.minor) +
                      ", " + std::to_string(n) + (n == 1 ? " scan" : " scans") +
                      (n ? " (" + codings + ")" : "") + ", " + std::to_string(records) +
                      " points, from " + (desc_.library.empty() ? desc_.guid : desc_.library);
}

bool E57Reader::NextScan() {
  while (scan_ < desc_.scans.size()) {
    const size_t i = scan_++;
    if (desc_.scans[i].record_count == 0) continue;
    section_ = std::make_unique<e57::SectionReader>(&file_, desc_.scans[i], plans_[i].wanted,
                                                    kMaxQueued);
    return true;
  }
  section_.reset();
  return false;
}

void E57Reader::ConvertPositions(size_t n, std::vector<Eigen::Vector3d>* out) const {
  const ScanPlan& plan = plans_[scan_ - 1];
  const double* a = columns_[plan.pos[0]].data();
  const double* b = columns_[plan.pos[1]].data();
  const double* c = columns_[plan.pos[2]].data();
  out->resize(n);
  Eigen::Vector3d* p = out->data();
  if (plan.spherical) {
    for (size_t i = 0; i < n; ++i) {
      const double r = a[i], az = b[i], el = c[i];
      const double h = r * std::cos(el);
      p[i] = Eigen::Vector3d(h * std::cos(az), h * std::sin(az), r * std::sin(el));
    }
  } else {
    for (size_t i = 0; i < n; ++i) p[i] = Eigen::Vector3d(a[i], b[i], c[i]);
  }
  if (!plan.identity) {
    for (size_t i = 0; i < n; ++i) p[i] = plan.rotation * p[i] + plan.translation;
  }
}

// Divides rather than multiplying by 255 / range, so that exact halves (100 of 0..200) round as
// the arithmetic says.
uint8_t ToColor8(double v, double lo, double range) {
  if (!(range > 0.0)) return 0;
  const double c = std::nearbyint((v - lo) * 255.0 / range);
  return static_cast<uint8_t>(c < 0.0 ? 0.0 : c > 255.0 ? 255.0 : c);
}

// Appends the valid points among the n decoded records at chunk index `at`; returns how many.
size_t E57Reader::Convert(size_t n, size_t at, PointCloud* chunk) const {
  const ScanPlan& plan = plans_[scan_ - 1];
  const double* invalid = plan.invalid >= 0 ? columns_[plan.invalid].data() : nullptr;
  const double* color_invalid = plan.color_invalid >= 0 ? columns_[plan.color_invalid].data() : nullptr;
  const double* intensity_invalid =
      plan.intensity_invalid >= 0 ? columns_[plan.intensity_invalid].data() : nullptr;
  const double* time_invalid = plan.time_invalid >= 0 ? columns_[plan.time_invalid].data() : nullptr;
  size_t out = at;
  for (size_t i = 0; i < n; ++i) {
    if (invalid && invalid[i] != 0.0) continue;
    chunk->positions[out] = positions_[i];
    if (chunk->schema.colors) {
      Rgb8 c = kDefaultColor;
      if (plan.rgb[0] >= 0 && !(color_invalid && color_invalid[i] != 0.0)) {
        c.r = ToColor8(columns_[plan.rgb[0]][i], plan.color_min[0], plan.color_range[0]);
        c.g = ToColor8(columns_[plan.rgb[1]][i], plan.color_min[1], plan.color_range[1]);
        c.b = ToColor8(columns_[plan.rgb[2]][i], plan.color_min[2], plan.color_range[2]);
      }
      chunk->colors[out] = c;
    }
    if (intensity_scalar_ >= 0) {
      const bool ok = plan.intensity >= 0 && !(intensity_invalid && intensity_invalid[i] != 0.0);
      chunk->scalars[intensity_scalar_].f32[out] =
          ok ? static_cast<float>(columns_[plan.intensity][i]) : 0.0f;
    }
    if (time_scalar_ >= 0) {
      const bool ok = plan.time >= 0 && !(time_invalid && time_invalid[i] != 0.0);
      chunk->scalars[time_scalar_].f64[out] = ok ? columns_[plan.time][i] : 0.0;
    }
    ++out;
  }
  return out - at;
}

size_t E57Reader::Read(size_t max_points, PointCloud* chunk) {
  CANDI_CHECK(max_points > 0) << "Read needs max_points > 0";
  PrepareChunk(chunk);
  size_t filled = 0;
  chunk->Resize(0);
  while (filled < max_points) {
    if (!section_ && !NextScan()) break;
    const size_t n = section_->Next(std::min(kBatch, max_points - filled), &columns_);
    if (n == 0) {
      section_.reset();
      continue;
    }
    ConvertPositions(n, &positions_);
    chunk->Resize(filled + n);
    filled += Convert(n, filled, chunk);
  }
  chunk->Resize(filled);
  points_read_ += filled;
  return filled;
}

}  // namespace

std::unique_ptr<PointReader> OpenE57Reader(const std::string& path,
                                           const PointReadOptions& options) {
  return std::make_unique<E57Reader>(path, options);
}

std::vector<E57ScanInfo> ListE57Scans(const std::string& path) {
  e57::PagedReader file(path);
  const e57::FileDesc desc = e57::ParseE57Xml(path, file.ReadXml(), file.header().physical_length);
  std::vector<E57ScanInfo> out;
  for (const ScanDesc& scan : desc.scans) {
    out.push_back({scan.name.empty() ? scan.guid : scan.name, scan.rotation, scan.translation,
                   scan.record_count});
  }
  return out;
}

std::unique_ptr<PointReader> OpenE57ScanReader(const std::string& path, size_t scan,
                                               const PointReadOptions& options) {
  if (scan > 1000000000) throw InputError(path, "", "has no scan " + std::to_string(scan));
  return std::make_unique<E57Reader>(path, options, static_cast<int>(scan));
}

}  // namespace candi::io
