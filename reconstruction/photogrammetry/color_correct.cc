#include "reconstruction/photogrammetry/color_correct.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"
#include "io/csv_table.h"

namespace candi::photogrammetry {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRankTolerance = 1e-6;  // smallest/largest singular value: rank-deficient below
constexpr double kPoorTolerance = 1e-2;  // ... poorly conditioned below

Eigen::Vector3d ReadRgb(const io::CsvTable& t, const io::CsvTable::Row& row,
                        const std::string& prefix) {
  Eigen::Vector3d v;
  const char* channel[3] = {"_r", "_g", "_b"};
  for (int c = 0; c < 3; ++c) {
    const std::string column = prefix + channel[c];
    v[c] = t.Number(row, column);
    if (v[c] < 0 || v[c] > 255) t.Fail(row, column, t.Text(row, column) + "; must be in 0..255");
  }
  return v;
}

Eigen::Vector3d Linear(const Eigen::Vector3d& srgb255) {
  return Eigen::Vector3d(SrgbToLinear(srgb255[0] / 255), SrgbToLinear(srgb255[1] / 255),
                         SrgbToLinear(srgb255[2] / 255));
}

Eigen::Vector3d Encode(const Eigen::Vector3d& linear) {
  return 255.0 * Eigen::Vector3d(LinearToSrgb(linear[0]), LinearToSrgb(linear[1]),
                                 LinearToSrgb(linear[2]));
}

// Least squares over the patches with use[i]: rows [meas_lin 1] -> ref_lin.
ColorMatrix Solve(const std::vector<ColorPatch>& patches, const std::vector<bool>& use,
                  double* conditioning) {
  const long n = std::count(use.begin(), use.end(), true);
  Eigen::MatrixXd a(n, 4), b(n, 3);
  long row = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    if (!use[i]) continue;
    a.row(row) << Linear(patches[i].measured).transpose(), 1.0;
    b.row(row++) = Linear(patches[i].reference).transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::Vector4d s = svd.singularValues();
  if (conditioning) *conditioning = s[0] > 0 ? s[3] / s[0] : 0;
  return svd.solve(b).transpose();
}

double PredictionError(const ColorMatrix& m, const ColorPatch& p) {
  return DeltaE2000(SrgbToLab(ApplyColorMatrix(m, p.measured)), SrgbToLab(p.reference));
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Index of the patch to remove, or -1: the worst leave-one-out error above the threshold.
int WorstOutlier(const ColorCorrectionOptions& o, const std::vector<ColorPatch>& patches,
                 const std::vector<bool>& use) {
  std::vector<double> errors;
  std::vector<size_t> index;
  for (size_t i = 0; i < patches.size(); ++i) {
    if (!use[i]) continue;
    std::vector<bool> others = use;
    others[i] = false;
    errors.push_back(PredictionError(Solve(patches, others, nullptr), patches[i]));
    index.push_back(i);
  }
  const double median = Median(errors);
  std::vector<double> dev;
  for (double e : errors) dev.push_back(std::abs(e - median));
  const double threshold = std::max(o.outlier_delta_e, median + o.outlier_k * 1.4826 * Median(dev));
  const size_t worst = static_cast<size_t>(std::max_element(errors.begin(), errors.end()) - errors.begin());
  return errors[worst] > threshold ? static_cast<int>(index[worst]) : -1;
}

template <typename T>
void ApplyToImage(const ColorMatrix& m, double max_value, Image<T>* image) {
  if (image->channels() < 3) {
    throw std::invalid_argument("colour correction needs an RGB or RGBA image; this one has " +
                                std::to_string(image->channels()) + " channel(s)");
  }
  const size_t levels = static_cast<size_t>(max_value) + 1;
  std::vector<double> decode(levels);
  for (size_t v = 0; v < levels; ++v) decode[v] = SrgbToLinear(static_cast<double>(v) / max_value);
  for (int y = 0; y < image->height(); ++y) {
    for (int x = 0; x < image->width(); ++x) {
      T* p = &image->at(x, y);
      const Eigen::Vector3d lin = m * Eigen::Vector4d(decode[p[0]], decode[p[1]], decode[p[2]], 1.0);
      for (int c = 0; c < 3; ++c) {
        p[c] = static_cast<T>(std::lround(LinearToSrgb(lin[c]) * max_value));
      }
    }
  }
}

}  // namespace

double SrgbToLinear(double v) {
  return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

double LinearToSrgb(double v) {
  v = std::clamp(v, 0.0, 1.0);
  return v <= 0.0031308 ? 12.92 * v : 1.055 * std::pow(v, 1.0 / 2.4) - 0.055;
}

Eigen::Vector3d SrgbToLab(const Eigen::Vector3d& srgb255) {
  Eigen::Matrix3d to_xyz;  // IEC 61966-2-1, D65
  to_xyz << 0.4124564, 0.3575761, 0.1804375, 0.2126729, 0.7151522, 0.0721750, 0.0193339,
      0.1191920, 0.9503041;
  const Eigen::Vector3d white(0.95047, 1.0, 1.08883);
  const Eigen::Vector3d xyz = (to_xyz * Linear(srgb255)).cwiseQuotient(white);
  auto f = [](double t) {
    constexpr double d = 6.0 / 29.0;
    return t > d * d * d ? std::cbrt(t) : t / (3 * d * d) + 4.0 / 29.0;
  };
  const double fx = f(xyz[0]), fy = f(xyz[1]), fz = f(xyz[2]);
  return Eigen::Vector3d(116 * fy - 16, 500 * (fx - fy), 200 * (fy - fz));
}

double DeltaE2000(const Eigen::Vector3d& lab1, const Eigen::Vector3d& lab2) {
  const double deg = kPi / 180;
  auto pow7 = [](double v) { return std::pow(v, 7); };
  const double c_bar = 0.5 * (std::hypot(lab1[1], lab1[2]) + std::hypot(lab2[1], lab2[2]));
  const double g = 0.5 * (1 - std::sqrt(pow7(c_bar) / (pow7(c_bar) + pow7(25))));
  const double a1 = (1 + g) * lab1[1], a2 = (1 + g) * lab2[1];
  const double c1 = std::hypot(a1, lab1[2]), c2 = std::hypot(a2, lab2[2]);
  auto hue = [&](double b, double a) {
    if (a == 0 && b == 0) return 0.0;
    const double h = std::atan2(b, a) / deg;
    return h < 0 ? h + 360 : h;
  };
  const double h1 = hue(lab1[2], a1), h2 = hue(lab2[2], a2);
  double dh = 0;
  if (c1 * c2 != 0) {
    dh = h2 - h1;
    if (dh > 180) dh -= 360;
    if (dh < -180) dh += 360;
  }
  const double d_l = lab2[0] - lab1[0], d_c = c2 - c1;
  const double d_h = 2 * std::sqrt(c1 * c2) * std::sin(dh * deg / 2);
  const double l_bar = 0.5 * (lab1[0] + lab2[0]), cp_bar = 0.5 * (c1 + c2);
  double h_bar = h1 + h2;
  if (c1 * c2 != 0) {
    if (std::abs(h1 - h2) <= 180) {
      h_bar /= 2;
    } else {
      h_bar = h_bar < 360 ? (h_bar + 360) / 2 : (h_bar - 360) / 2;
    }
  }
  const double t = 1 - 0.17 * std::cos((h_bar - 30) * deg) + 0.24 * std::cos(2 * h_bar * deg) +
                   0.32 * std::cos((3 * h_bar + 6) * deg) - 0.20 * std::cos((4 * h_bar - 63) * deg);
  const double d_theta = 30 * std::exp(-std::pow((h_bar - 275) / 25, 2));
  const double r_c = 2 * std::sqrt(pow7(cp_bar) / (pow7(cp_bar) + pow7(25)));
  const double l50 = (l_bar - 50) * (l_bar - 50);
  const double s_l = 1 + 0.015 * l50 / std::sqrt(20 + l50);
  const double s_c = 1 + 0.045 * cp_bar, s_h = 1 + 0.015 * cp_bar * t;
  const double r_t = -std::sin(2 * d_theta * deg) * r_c;
  const double x = d_l / s_l, y = d_c / s_c, z = d_h / s_h;
  return std::sqrt(x * x + y * y + z * z + r_t * y * z);
}

std::vector<ColorPatch> ReadColorPatches(const std::string& path) {
  const io::CsvTable t =
      io::CsvTable::Read(path, {"patch", "measured_r", "measured_g", "measured_b", "reference_r",
                                "reference_g", "reference_b"});
  std::vector<ColorPatch> patches;
  for (const io::CsvTable::Row& row : t.rows()) {
    patches.push_back({t.Text(row, "patch"), ReadRgb(t, row, "measured"),
                       ReadRgb(t, row, "reference"), row.line});
  }
  return patches;
}

std::vector<PatchQuad> ReadPatchQuads(const std::string& path) {
  const io::CsvTable t =
      io::CsvTable::Read(path, {"patch", "x0", "y0", "x1", "y1", "x2", "y2", "x3", "y3",
                                "reference_r", "reference_g", "reference_b"});
  std::vector<PatchQuad> quads;
  for (const io::CsvTable::Row& row : t.rows()) {
    PatchQuad q;
    q.name = t.Text(row, "patch");
    q.line = row.line;
    for (int k = 0; k < 4; ++k) {
      const std::string i = std::to_string(k);
      q.corners[k] = Eigen::Vector2d(t.Number(row, "x" + i), t.Number(row, "y" + i));
    }
    q.reference = ReadRgb(t, row, "reference");
    quads.push_back(q);
  }
  return quads;
}

std::vector<ColorPatch> SamplePatches(const Image8& image, const std::vector<PatchQuad>& quads,
                                      const std::string& quads_path) {
  if (image.channels() < 3) {
    throw InputError(quads_path, "", "the card image must be RGB or RGBA");
  }
  std::vector<ColorPatch> patches;
  for (const PatchQuad& q : quads) {
    const std::string line = "line " + std::to_string(q.line);
    for (const Eigen::Vector2d& c : q.corners) {
      if (c.x() < -0.5 || c.y() < -0.5 || c.x() > image.width() - 0.5 || c.y() > image.height() - 0.5) {
        throw InputError(quads_path, line, "patch '" + q.name + "' reaches outside the " +
                                               std::to_string(image.width()) + "x" +
                                               std::to_string(image.height()) + " image");
      }
    }
    const double side = std::max((q.corners[1] - q.corners[0]).norm(), (q.corners[2] - q.corners[1]).norm());
    const int steps = std::max(2, static_cast<int>(std::ceil(side)));  // ~2 samples per pixel
    std::array<std::vector<double>, 3> values;
    for (int i = 0; i <= steps; ++i) {
      for (int j = 0; j <= steps; ++j) {
        const double s = 0.25 + 0.5 * i / steps, t = 0.25 + 0.5 * j / steps;
        const Eigen::Vector2d p = (1 - s) * (1 - t) * q.corners[0] + s * (1 - t) * q.corners[1] +
                                  s * t * q.corners[2] + (1 - s) * t * q.corners[3];
        const int x = static_cast<int>(std::lround(p.x())), y = static_cast<int>(std::lround(p.y()));
        for (int c = 0; c < 3; ++c) values[c].push_back(image.at(x, y, c));
      }
    }
    ColorPatch patch{q.name, Eigen::Vector3d::Zero(), q.reference, q.line};
    for (int c = 0; c < 3; ++c) patch.measured[c] = Median(values[c]);
    patches.push_back(patch);
  }
  return patches;
}

void ColorCorrectionOptions::Check() const {
  CANDI_CHECK_OPTION_GT(outlier_delta_e, 0);
  CANDI_CHECK_OPTION_GT(outlier_k, 0);
  CANDI_CHECK_OPTION_GE(max_outliers, 0);
}

ColorCorrection FitColorCorrection(const ColorCorrectionOptions& options,
                                   const std::vector<ColorPatch>& patches) {
  options.Check();
  if (patches.size() < 4) {
    throw InputError(std::to_string(patches.size()) +
                     " colour patches; a 3x4 colour matrix needs at least 4");
  }
  ColorCorrection r;
  std::vector<bool> use(patches.size(), true);
  Solve(patches, use, &r.conditioning);
  if (r.conditioning < kRankTolerance) {
    throw InputError(
        "the colour patches do not span RGB (smallest/largest singular value of the "
        "design " +
        FormatSignificant(r.conditioning, 3) +
        "; all grey?): the 3x4 colour matrix is undetermined; use a card with "
        "coloured patches");
  }
  if (r.conditioning < kPoorTolerance) {
    r.warnings.push_back("the colour patches barely span RGB (conditioning " +
                         FormatSignificant(r.conditioning, 3) +
                         "): the matrix is poorly determined");
  }
  const size_t max_removed = std::min<size_t>(static_cast<size_t>(options.max_outliers),
                                              patches.size() > 5 ? patches.size() - 5 : 0);
  for (size_t removed = 0; removed < max_removed; ++removed) {
    const int worst = WorstOutlier(options, patches, use);
    if (worst < 0) break;
    use[static_cast<size_t>(worst)] = false;
    r.warnings.push_back("patch '" + patches[static_cast<size_t>(worst)].name +
                         "' disagrees with the others; left out of the fit");
  }
  r.matrix = Solve(patches, use, &r.conditioning);
  int kept = 0;
  for (size_t i = 0; i < patches.size(); ++i) {
    const ColorPatch& p = patches[i];
    const Eigen::Vector3d ref = SrgbToLab(p.reference);
    PatchDeltaE d{p.name, DeltaE2000(SrgbToLab(p.measured), ref), PredictionError(r.matrix, p), !use[i]};
    r.patches.push_back(d);
    if (d.outlier) continue;
    ++kept;
    r.mean_before += d.before;
    r.mean_after += d.after;
    r.max_before = std::max(r.max_before, d.before);
    r.max_after = std::max(r.max_after, d.after);
  }
  r.mean_before /= kept;
  r.mean_after /= kept;
  return r;
}

Eigen::Vector3d ApplyColorMatrix(const ColorMatrix& m, const Eigen::Vector3d& srgb255) {
  return Encode(m * Linear(srgb255).homogeneous());
}

void ApplyColorMatrix(const ColorMatrix& m, Image8* image) { ApplyToImage(m, 255.0, image); }
void ApplyColorMatrix(const ColorMatrix& m, Image16* image) { ApplyToImage(m, 65535.0, image); }

void ApplyColorMatrix(const ColorMatrix& m, PointCloud* cloud) {
  CANDI_CHECK(cloud->schema.colors) << "the cloud has no colours";
  for (Rgb8& c : cloud->colors) {
    const Eigen::Vector3d v = ApplyColorMatrix(m, Eigen::Vector3d(c.r, c.g, c.b));
    c = Rgb8{static_cast<uint8_t>(std::lround(v[0])), static_cast<uint8_t>(std::lround(v[1])),
             static_cast<uint8_t>(std::lround(v[2]))};
  }
}

}  // namespace candi::photogrammetry
