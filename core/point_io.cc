#include "core/point_io.h"

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/binary_file.h"
#include "core/check.h"
#include "core/e57_io.h"
#include "core/las_io.h"
#include "core/ply_io.h"
#include "core/text_format.h"
#include "core/xyz_io.h"

namespace candi {

std::string PointFormatName(PointFormat format) {
  switch (format) {
    case PointFormat::kPly: return "PLY";
    case PointFormat::kLas: return "LAS";
    case PointFormat::kXyz: return "XYZ";
    case PointFormat::kPts: return "PTS";
    case PointFormat::kE57: return "E57";
  }
  return "?";
}

void PointReader::PrepareChunk(PointCloud* chunk) const {
  if (chunk->schema != info_.schema) {
    chunk->positions.clear();
    chunk->SetSchema(info_.schema);
  }
  chunk->frame = info_.frame;
  chunk->meta = info_.meta;
}

void PointWriteOptions::Check() const {
  if (las_version_minor != -1 && (las_version_minor < 2 || las_version_minor > 4)) {
    throw std::invalid_argument("PointWriteOptions::las_version_minor = " +
                                std::to_string(las_version_minor) + "; must be -1, 2, 3 or 4");
  }
  const int f = las_point_format;
  if (f != -1 && !((f >= 0 && f <= 3) || (f >= 6 && f <= 8))) {
    throw std::invalid_argument("PointWriteOptions::las_point_format = " + std::to_string(f) +
                                "; must be -1, 0-3 or 6-8");
  }
  if (las_scale && !(las_scale->minCoeff() > 0.0 && las_scale->allFinite())) {
    throw std::invalid_argument("PointWriteOptions::las_scale must be finite and > 0");
  }
}

namespace {

std::string Extension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot + 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

enum class Content { kEmpty, kPly, kLas, kLaz, kE57, kAsciiDxf, kBinaryDxf, kText, kBinary };

Content Sniff(const std::string& head) {
  if (head.empty()) return Content::kEmpty;
  if (head.rfind("ply\n", 0) == 0 || head.rfind("ply\r\n", 0) == 0) return Content::kPly;
  if (head.rfind("LASF", 0) == 0) {
    // Point data format byte at offset 104: LASzip sets bit 7 (and 6) for compressed data.
    if (head.size() > 104 && (static_cast<uint8_t>(head[104]) & 0xC0) != 0) return Content::kLaz;
    return Content::kLas;
  }
  if (head.rfind("AutoCAD Binary DXF", 0) == 0) return Content::kBinaryDxf;
  if (head.rfind("ASTM-E57", 0) == 0) return Content::kE57;
  size_t i = 0;
  while (i < head.size() && std::isspace(static_cast<unsigned char>(head[i]))) ++i;
  if (head.compare(i, 1, "0") == 0) {
    size_t j = i + 1;
    while (j < head.size() && std::isspace(static_cast<unsigned char>(head[j]))) ++j;
    if (head.compare(j, 7, "SECTION") == 0) return Content::kAsciiDxf;
  }
  for (unsigned char c : head) {
    if (c == 0 || (c < 32 && c != '\n' && c != '\r' && c != '\t')) return Content::kBinary;
  }
  return Content::kText;
}

std::string ContentName(Content c) {
  switch (c) {
    case Content::kEmpty: return "empty";
    case Content::kPly: return "PLY";
    case Content::kLas: return "LAS";
    case Content::kLaz: return "LAZ (compressed LAS)";
    case Content::kE57: return "E57";
    case Content::kAsciiDxf: return "a DXF drawing";
    case Content::kBinaryDxf: return "a binary DXF drawing";
    case Content::kText: return "text";
    case Content::kBinary: return "binary data";
  }
  return "?";
}

}  // namespace

PointFormat OutputPointFormat(const std::string& path) {
  const std::string ext = Extension(path);
  if (ext == "ply") return PointFormat::kPly;
  if (ext == "las") return PointFormat::kLas;
  if (ext == "pts") return PointFormat::kPts;
  if (ext == "e57") return PointFormat::kE57;
  if (ext == "xyz" || ext == "txt" || ext == "asc" || ext == "csv") return PointFormat::kXyz;
  if (ext == "laz") throw InputError(path, "", "writing LAZ is not supported; write .las");
  throw InputError(path, "", "unknown point-file extension '." + ext +
                                 "' (known: .ply .las .xyz .txt .asc .csv .pts .e57)");
}

PointFormat DetectPointFormat(const std::string& path) {
  BinaryFile file(path);
  const Content content = Sniff(file.Peek(4096));
  const std::string ext = Extension(path);
  if (content == Content::kEmpty) throw InputError(path, "byte 0", "empty file");
  if (content == Content::kAsciiDxf || content == Content::kBinaryDxf || ext == "dxf") {
    throw InputError(path, "", "is " + ContentName(content == Content::kText ? Content::kAsciiDxf : content) +
                                   ", not a point file; CAD sections go through `candi foundation`");
  }
  PointFormat format;
  Content expected;
  if (ext == "ply") {
    format = PointFormat::kPly;
    expected = Content::kPly;
  } else if (ext == "las") {
    format = PointFormat::kLas;
    expected = content == Content::kLaz ? Content::kLaz : Content::kLas;  // LAZ named .las
  } else if (ext == "laz") {
    format = PointFormat::kLas;  // the LAS reader decodes LAZ (and reads a plain LAS so named)
    expected = content == Content::kLas ? Content::kLas : Content::kLaz;
  } else if (ext == "e57") {
    format = PointFormat::kE57;
    expected = Content::kE57;
  } else if (ext == "pts" || ext == "xyz" || ext == "txt" || ext == "asc" || ext == "csv") {
    format = ext == "pts" ? PointFormat::kPts : PointFormat::kXyz;
    expected = Content::kText;
  } else {
    throw InputError(path, "", "unknown point-file extension '." + ext + "' (content looks like " +
                                   ContentName(content) + "; known: .ply .las .laz .xyz .txt .asc .csv .pts .e57)");
  }
  if (content != expected) {
    throw InputError(path, "byte 0", "extension says " + PointFormatName(format) +
                                         " but the content is " + ContentName(content));
  }
  return format;
}

std::unique_ptr<PointReader> OpenPointReader(const std::string& path,
                                             const PointReadOptions& options) {
  switch (DetectPointFormat(path)) {
    case PointFormat::kPly: return OpenPlyReader(path, options);
    case PointFormat::kLas: return OpenLasReader(path, options);
    case PointFormat::kXyz: return OpenXyzReader(path, /*pts=*/false, options);
    case PointFormat::kPts: return OpenXyzReader(path, /*pts=*/true, options);
    case PointFormat::kE57: return OpenE57Reader(path, options);
  }
  return nullptr;
}

std::unique_ptr<PointWriter> OpenPointWriter(const std::string& path, const PointWriteSpec& spec,
                                             const PointWriteOptions& options) {
  options.Check();
  switch (OutputPointFormat(path)) {
    case PointFormat::kPly: return OpenPlyWriter(path, spec, options);
    case PointFormat::kLas: return OpenLasWriter(path, spec, options);
    case PointFormat::kXyz: return OpenXyzWriter(path, /*pts=*/false, spec, options);
    case PointFormat::kPts: return OpenXyzWriter(path, /*pts=*/true, spec, options);
    case PointFormat::kE57: return OpenE57Writer(path, spec, options);
  }
  return nullptr;
}

PointCloud ReadPointCloud(const std::string& path, const PointReadOptions& options) {
  auto reader = OpenPointReader(path, options);
  PointCloud cloud;
  cloud.SetSchema(reader->info().schema);
  cloud.frame = reader->info().frame;
  cloud.meta = reader->info().meta;
  if (reader->info().count != kUnknownCount) cloud.Reserve(reader->info().count);
  PointCloud chunk;
  while (reader->Read(1 << 20, &chunk) > 0) cloud.Append(chunk);
  return cloud;
}

void WritePointCloud(const std::string& path, const PointCloud& cloud,
                     const PointWriteOptions& options) {
  cloud.CheckConsistent();
  PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, cloud.size()};
  auto writer = OpenPointWriter(path, spec, options);
  writer->Write(cloud);
  writer->Close();
}

std::string ShiftSidecarPath(const std::string& path) { return path + ".shift.json"; }

void WriteShiftSidecar(const std::string& path, const LocalFrame& frame) {
  struct stat st;
  const uint64_t size = stat(path.c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_size) : 0;
  const std::string json = "{\n  \"candi_shift\": [" + FormatDouble(frame.origin.x()) + ", " +
                           FormatDouble(frame.origin.y()) + ", " + FormatDouble(frame.origin.z()) +
                           "],\n  \"meaning\": \"world = local + candi_shift (metres)\",\n" +
                           "  \"file_size\": " + std::to_string(size) + "\n}\n";
  WriteFileAtomic(ShiftSidecarPath(path), json);
}

std::optional<LocalFrame> ReadShiftSidecar(const std::string& path) {
  const std::string sidecar = ShiftSidecarPath(path);
  struct stat st, st_data;
  if (stat(sidecar.c_str(), &st) != 0 || stat(path.c_str(), &st_data) != 0) return std::nullopt;
  const std::string text = ReadFileToString(sidecar);
  const size_t key = text.find("\"candi_shift\"");
  const size_t size_key = text.find("\"file_size\"");
  if (key == std::string::npos || size_key == std::string::npos) {
    throw InputError(sidecar, "", "not a candi shift sidecar (no \"candi_shift\" / \"file_size\")");
  }
  double x, y, z;
  unsigned long long size = 0;
  const size_t open = text.find('[', key);
  if (open == std::string::npos ||
      std::sscanf(text.c_str() + open, "[ %lf , %lf , %lf ]", &x, &y, &z) != 3 ||
      std::sscanf(text.c_str() + text.find(':', size_key) + 1, " %llu", &size) != 1) {
    throw InputError(sidecar, "", "malformed candi_shift or file_size");
  }
  if (size != static_cast<unsigned long long>(st_data.st_size)) return std::nullopt;  // stale
  LocalFrame frame;
  frame.origin = Eigen::Vector3d(x, y, z);
  if (!frame.origin.allFinite()) throw InputError(sidecar, "", "candi_shift is not finite");
  return frame;
}

}  // namespace candi
