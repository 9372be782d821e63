#include "io/point_format.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <string>

#include "core/binary_file.h"
#include "core/check.h"

namespace candi::io {

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
  if (ext == "las" || ext == "laz") return PointFormat::kLas;  // the LAS writer compresses .laz
  if (ext == "pts") return PointFormat::kPts;
  if (ext == "e57") return PointFormat::kE57;
  if (ext == "xyz" || ext == "txt" || ext == "asc" || ext == "csv") return PointFormat::kXyz;
  throw InputError(path, "", "unknown point-file extension '." + ext +
                                 "' (known: .ply .las .laz .xyz .txt .asc .csv .pts .e57)");
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

}  // namespace candi::io
