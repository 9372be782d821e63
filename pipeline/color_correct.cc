#include "pipeline/color_correct.h"

#include <cctype>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "io/image/png_io.h"
#include "io/point_io.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
namespace pg = candi::photogrammetry;

bool IsPng(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

std::vector<pg::ColorPatch> Patches(const ColorCard& card) {
  if (!card.patches.empty()) return pg::ReadColorPatches(card.patches);
  const io::PngImage photo = io::ReadPng(card.card);
  if (photo.bit_depth != 8) throw InputError(card.card, "", "the card photo must be an 8-bit PNG");
  return pg::SamplePatches(photo.image8, pg::ReadPatchQuads(card.corners), card.corners);
}

std::string ColorCorrectionJson(const pg::ColorCorrection& c) {
  nlohmann::json j;
  j["matrix_linear_rgb"] = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) {
    j["matrix_linear_rgb"].push_back(
        {c.matrix(r, 0), c.matrix(r, 1), c.matrix(r, 2), c.matrix(r, 3)});
  }
  j["delta_e"] = "CIEDE2000";
  for (const pg::PatchDeltaE& p : c.patches) {
    j["patches"].push_back(
        {{"name", p.name}, {"before", p.before}, {"after", p.after}, {"outlier", p.outlier}});
  }
  j["mean_before"] = c.mean_before;
  j["mean_after"] = c.mean_after;
  j["max_before"] = c.max_before;
  j["max_after"] = c.max_after;
  j["warnings"] = c.warnings;
  return j.dump(2) + "\n";
}

void CorrectPointFile(const std::string& input, const std::string& output,
                      const pg::ColorMatrix& m) {
  PointCloud cloud = io::ReadPointCloud(input);
  if (!cloud.schema.colors) throw InputError(input, "", "the points have no colours");
  pg::ApplyColorMatrix(m, &cloud);
  io::WritePointCloud(output, cloud);
}

void CorrectImage(const std::string& input, const std::string& output, const pg::ColorMatrix& m) {
  io::PngImage png = io::ReadPng(input);
  Image8& image8 = png.image8;
  const int channels = png.bit_depth == 8 ? image8.channels() : png.image16.channels();
  if (channels < 3) throw InputError(input, "", "a grey image cannot be colour-corrected");
  if (png.bit_depth == 8) {
    pg::ApplyColorMatrix(m, &image8);
    io::WritePng(output, image8, png.text);
  } else {
    pg::ApplyColorMatrix(m, &png.image16);
    io::WritePng(output, png.image16, png.text);
  }
}

}  // namespace

pg::ColorCorrection ColorCorrectFile(
    const pg::ColorCorrectionOptions& options, const ColorCard& card, const std::string& input,
    const std::string& output, const std::function<void(const pg::ColorCorrection&)>& fitted) {
  options.Check();
  if (card.patches.empty() == (card.card.empty() || card.corners.empty())) {
    throw std::invalid_argument("give either --patches or both --card and --corners");
  }
  const bool png = IsPng(input);
  if (png != IsPng(output))
    throw std::invalid_argument("IN and OUT must both be PNG images or both point files");
  if (!png) {
    io::DetectPointFormat(input);
    io::OutputPointFormat(output);
  } else if (!fs::is_regular_file(input)) {
    throw InputError(input, "", "cannot read the image (no such file)");
  }
  const pg::ColorCorrection c = pg::FitColorCorrection(options, Patches(card));
  if (fitted) fitted(c);
  for (const std::string& w : c.warnings) LogWarning(w);
  if (png) {
    CorrectImage(input, output, c.matrix);
  } else {
    CorrectPointFile(input, output, c.matrix);
  }
  WriteFileAtomic(output + ".colorcorrect.json", ColorCorrectionJson(c));
  return c;
}

}  // namespace candi::pipeline
