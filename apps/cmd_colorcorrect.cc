// candi colorcorrect IN -o OUT (--patches P.csv | --card CARD.png --corners C.csv): fits a 3x4
// colour matrix in linear RGB to a colour card's patches (reconstruction/photogrammetry/
// color_correct.h), prints CIEDE2000 per patch before and after, and applies the matrix to IN, a
// PNG image (8 or 16 bit, RGB or RGBA) or a point file with colours. Writes OUT.colorcorrect.json.
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/color_correct.h"

namespace candi::app {

namespace {

namespace pg = candi::photogrammetry;

bool IsPng(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

std::vector<pg::ColorPatch> Patches(const ColorCorrectArgs& a) {
  if (!a.patches.empty()) return pg::ReadColorPatches(a.patches);
  const io::PngImage card = io::ReadPng(a.card);
  if (card.bit_depth != 8) throw InputError(a.card, "", "the card photo must be an 8-bit PNG");
  return pg::SamplePatches(card.image8, pg::ReadPatchQuads(a.corners), a.corners);
}

void PrintReport(const pg::ColorCorrection& c) {
  std::printf("%-16s %10s %10s  %s\n", "patch", "dE00 before", "dE00 after", "status");
  for (const pg::PatchDeltaE& p : c.patches) {
    std::printf("%-16s %10.2f %10.2f  %s\n", p.name.c_str(), p.before, p.after,
                p.outlier ? "OUTLIER (not fitted)" : "ok");
  }
  std::printf("%-16s %10.2f %10.2f\n%-16s %10.2f %10.2f\n", "mean (fitted)", c.mean_before,
              c.mean_after, "max (fitted)", c.max_before, c.max_after);
  std::printf("colour difference: CIEDE2000, CIELAB D65; matrix (linear RGB, out = M [in; 1]):\n");
  for (int r = 0; r < 3; ++r) {
    std::printf("  %9.5f %9.5f %9.5f %9.5f\n", c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2),
                c.matrix(r, 3));
  }
  for (const std::string& w : c.warnings) std::printf("warning: %s\n", w.c_str());
}

std::string ReportJson(const pg::ColorCorrection& c) {
  nlohmann::json j;
  j["matrix_linear_rgb"] = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) {
    j["matrix_linear_rgb"].push_back({c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2), c.matrix(r, 3)});
  }
  j["delta_e"] = "CIEDE2000";
  for (const pg::PatchDeltaE& p : c.patches) {
    j["patches"].push_back({{"name", p.name}, {"before", p.before}, {"after", p.after},
                            {"outlier", p.outlier}});
  }
  j["mean_before"] = c.mean_before;
  j["mean_after"] = c.mean_after;
  j["max_before"] = c.max_before;
  j["max_after"] = c.max_after;
  j["warnings"] = c.warnings;
  return j.dump(2) + "\n";
}

void CorrectPointFile(const ColorCorrectArgs& a, const pg::ColorMatrix& m) {
  PointCloud cloud = io::ReadPointCloud(a.input);
  if (!cloud.schema.colors) throw InputError(a.input, "", "the points have no colours");
  pg::ApplyColorMatrix(m, &cloud);
  io::WritePointCloud(a.output, cloud);
}

void CorrectImage(const ColorCorrectArgs& a, const pg::ColorMatrix& m) {
  io::PngImage png = io::ReadPng(a.input);
  Image8& image8 = png.image8;
  const int channels = png.bit_depth == 8 ? image8.channels() : png.image16.channels();
  if (channels < 3) throw InputError(a.input, "", "a grey image cannot be colour-corrected");
  if (png.bit_depth == 8) {
    pg::ApplyColorMatrix(m, &image8);
    io::WritePng(a.output, image8, png.text);
  } else {
    pg::ApplyColorMatrix(m, &png.image16);
    io::WritePng(a.output, png.image16, png.text);
  }
}

}  // namespace

int RunColorCorrect(const ColorCorrectArgs& args) {
  pg::ColorCorrectionOptions options;
  options.outlier_delta_e = args.outlier_delta_e;
  options.max_outliers = args.max_outliers;
  options.Check();
  if (args.patches.empty() == (args.card.empty() || args.corners.empty())) {
    throw std::invalid_argument("give either --patches or both --card and --corners");
  }
  const bool png = IsPng(args.input);
  if (png != IsPng(args.output)) {
    throw std::invalid_argument("IN and OUT must both be PNG images or both point files");
  }
  if (!png) {
    io::DetectPointFormat(args.input);
    io::OutputPointFormat(args.output);
  } else if (!std::filesystem::is_regular_file(args.input)) {
    throw InputError(args.input, "", "cannot read the image (no such file)");
  }
  const pg::ColorCorrection c = pg::FitColorCorrection(options, Patches(args));
  PrintReport(c);
  for (const std::string& w : c.warnings) LogWarning(w);
  if (png) {
    CorrectImage(args, c.matrix);
  } else {
    CorrectPointFile(args, c.matrix);
  }
  WriteFileAtomic(args.output + ".colorcorrect.json", ReportJson(c));
  return kOk;
}

}  // namespace candi::app
