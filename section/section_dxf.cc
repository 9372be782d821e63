#include "section/section_dxf.h"

#include <dl_dxf.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"

namespace candi::section {

namespace {

// Beyond any survey coordinate (a unit error), and far inside dxflib's "%.16f" buffer of 256
// characters (fortified: a value past ~1e238 would abort the process).
constexpr double kMaxCoordinate = 1e12;
// AutoCAD's limit for symbol names, in characters.
constexpr size_t kMaxNameChars = 255;
// dxflib (and candi's ReadDxf) read lines of at most 1023 bytes; longer ones desynchronise the
// group code / value pairs.
constexpr size_t kMaxLineBytes = 1000;
// Characters AutoCAD refuses in symbol names (EXTNAMES); control characters are refused as well.
constexpr const char* kForbiddenInNames = "<>/\\\":;?*|,=`";
// Handles dxflib hands out (DL_Writer::handle, from 0x30) besides one per layer and entity:
// table, block and object records, 5 in dxflib 3.26. 0x100 leaves a wide margin for other
// versions; WriteSectionDxf checks it.
constexpr unsigned long kOtherHandles = 0x100;

// The code point starting at text[*pos], advancing *pos past it; -1 (advancing one byte) for
// bytes that are not UTF-8 (stray continuation bytes, overlong forms, surrogates, > U+10FFFF).
int32_t NextCodePoint(const std::string& text, size_t* pos) {
  const unsigned char lead = static_cast<unsigned char>(text[*pos]);
  const int length = lead < 0x80             ? 1
                     : (lead & 0xe0) == 0xc0 ? 2
                     : (lead & 0xf0) == 0xe0 ? 3
                     : (lead & 0xf8) == 0xf0 ? 4
                                             : 0;
  if (length == 1) return text[(*pos)++];
  int32_t cp = length == 2 ? lead & 0x1f : length == 3 ? lead & 0x0f : lead & 0x07;
  bool valid = length > 0 && *pos + length <= text.size();
  for (int k = 1; valid && k < length; ++k) {
    const unsigned char c = static_cast<unsigned char>(text[*pos + k]);
    valid = (c & 0xc0) == 0x80;
    cp = (cp << 6) | (c & 0x3f);
  }
  static const int32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
  valid = valid && cp >= kSmallest[length] && cp <= 0x10ffff && !(cp >= 0xd800 && cp <= 0xdfff);
  *pos += valid ? length : 1;
  return valid ? cp : -1;
}

// `text` (UTF-8) as DXF text in ANSI_1252 of at most max_chars characters and max_bytes bytes,
// as AutoCAD and ezdxf write DXF before 2007: ASCII and Latin-1 characters as their byte, other
// characters of the Basic Multilingual Plane as \U+XXXX (one character); control characters,
// characters in `forbidden`, invalid UTF-8 and characters beyond U+FFFF (which the escape cannot
// hold) become `replacement`.
std::string EncodeDxfText(const std::string& text, const char* forbidden, char replacement,
                          size_t max_chars, size_t max_bytes) {
  std::string out;
  size_t chars = 0;
  for (size_t pos = 0; pos < text.size() && chars < max_chars; ++chars) {
    const int32_t cp = NextCodePoint(text, &pos);
    const bool control = cp < 0x20 || (cp >= 0x7f && cp < 0xa0);
    char piece[8] = {replacement, '\0'};
    if (control || cp > 0xffff || (cp < 0x80 && std::strchr(forbidden, cp))) {
      // replaced
    } else if (cp <= 0xff) {
      piece[0] = static_cast<char>(cp);  // ANSI_1252 agrees with Latin-1 from 0xa0 up
    } else {
      std::snprintf(piece, sizeof(piece), "\\U+%04X", static_cast<unsigned>(cp));
    }
    if (out.size() + std::strlen(piece) > max_bytes) break;
    out += piece;
  }
  return out;
}

std::string LayerName(const std::string& name, const std::string& suffix) {
  if (name.empty()) return "0" + suffix;
  return EncodeDxfText(name, kForbiddenInNames, '_', kMaxNameChars - suffix.size(),
                       kMaxLineBytes - suffix.size()) +
         suffix;
}

std::string UpperAscii(std::string text) {
  for (char& c : text) c = (c >= 'a' && c <= 'z') ? static_cast<char>(c - 'a' + 'A') : c;
  return text;
}

// AutoCAD's colour index palette, 0xRRGGBB by index (0 unused): 1-9 named colours, 250-255
// greys, and 10-249 24 hues 15 degrees apart (10 red, 50 yellow, 90 green, ...), each at five
// values (255, 204, 153, 127, 76: index % 10 / 2) at full saturation (even index) or with the
// smallest component half the largest (odd index); the middle component steps in quarters.
// (Published tables differ slightly for the greys 250-255; these are libdxfrw's.)
const std::array<uint32_t, 256>& AciPalette() {
  static const std::array<uint32_t, 256> palette = [] {
    std::array<uint32_t, 256> p{};
    const uint32_t named[10] = {0,        0xff0000, 0xffff00, 0x00ff00, 0x00ffff,
                                0x0000ff, 0xff00ff, 0xffffff, 0x808080, 0xc0c0c0};
    std::copy(named, named + 10, p.begin());
    const int kValue[5] = {255, 204, 153, 127, 76};
    for (int aci = 10; aci < 250; ++aci) {
      const int hue = aci / 10 - 1, sector = hue / 4, step = hue % 4;
      const int max = kValue[aci % 10 / 2], min = aci % 2 ? max / 2 : 0;
      const auto ramp = [&](int quarters) { return min + (max - min) * quarters / 4; };
      const int rise = ramp(step), fall = ramp(4 - step);
      const int rgb[6][3] = {{max, rise, min}, {fall, max, min}, {min, max, rise},
                             {min, fall, max}, {rise, min, max}, {max, min, fall}};
      const int* c = rgb[sector];
      p[aci] = static_cast<uint32_t>(c[0] << 16 | c[1] << 8 | c[2]);
    }
    const uint32_t greys[6] = {0x333333, 0x5b5b5b, 0x848484, 0xadadad, 0xd6d6d6, 0xffffff};
    std::copy(greys, greys + 6, p.begin() + 250);
    return p;
  }();
  return palette;
}

void CheckLayer(const DxfLayerLines& layer) {
  CANDI_CHECK(layer.rgb <= 0xffffffu) << "layer '" << layer.name << "': rgb = 0x" << std::hex
                                      << layer.rgb << "; must be <= 0xffffff";
  for (size_t i = 0; i < layer.lines.size(); ++i) {
    const std::vector<Eigen::Vector2d>& points = layer.lines[i].points;
    CANDI_CHECK(points.size() <= 0x7fffffffu)
        << "layer '" << layer.name << "', polyline " << i << ": " << points.size()
        << " vertices; an LWPOLYLINE holds at most 2^31 - 1";
    for (size_t k = 0; k < points.size(); ++k) {
      const Eigen::Vector2d& p = points[k];
      CANDI_CHECK(p.allFinite() && p.cwiseAbs().maxCoeff() <= kMaxCoordinate)
          << "layer '" << layer.name << "', polyline " << i << ", vertex " << k << " = ("
          << FormatDouble(p.x()) << ", " << FormatDouble(p.y())
          << "); coordinates must be finite and within 1e12 m";
    }
  }
}

// DL_Dxf::writeHeader, with the variables of a metric drawing and a $HANDSEED (the next free
// handle: above every handle in the file) that grows with the drawing where dxflib's is FFFF.
void WriteHeader(const DxfWriteOptions& options, const Eigen::AlignedBox2d& extent,
                 unsigned long handle_seed, DL_WriterA& dw) {
  const std::string comment = EncodeDxfText(options.comment, "", ' ', kMaxLineBytes, kMaxLineBytes);
  if (!comment.empty()) dw.dxfString(999, comment);
  dw.comment("dxflib " DL_VERSION);
  dw.sectionHeader();
  dw.dxfString(9, "$ACADVER");
  dw.dxfString(1, "AC1015");
  dw.dxfString(9, "$DWGCODEPAGE");
  dw.dxfString(3, "ANSI_1252");
  dw.dxfString(9, "$HANDSEED");
  dw.dxfHex(5, static_cast<int>(handle_seed));
  dw.dxfString(9, "$INSUNITS");
  dw.dxfInt(70, 6);  // metres
  dw.dxfString(9, "$MEASUREMENT");
  dw.dxfInt(70, 1);  // metric
  if (!extent.isEmpty()) {
    dw.dxfString(9, "$EXTMIN");
    dw.coord(10, extent.min().x(), extent.min().y(), 0.0);
    dw.dxfString(9, "$EXTMAX");
    dw.coord(10, extent.max().x(), extent.max().y(), 0.0);
  }
  dw.sectionEnd();
}

// The tables dxflib's own writing example gives (what AutoCAD needs to open the file), with
// layer "0" and one layer per section.
void WriteTables(const std::vector<DxfLayerLines>& layers, const std::vector<std::string>& names,
                 bool true_colour, DL_Dxf& dxf, DL_WriterA& dw) {
  dw.sectionTables();
  dxf.writeVPort(dw);
  dw.tableLinetypes(3);
  dxf.writeLinetype(dw, DL_LinetypeData("BYBLOCK", "BYBLOCK", 0, 0, 0.0));
  dxf.writeLinetype(dw, DL_LinetypeData("BYLAYER", "BYLAYER", 0, 0, 0.0));
  dxf.writeLinetype(dw, DL_LinetypeData("CONTINUOUS", "Continuous", 0, 0, 0.0));
  dw.tableEnd();
  const bool has_zero = std::find(names.begin(), names.end(), "0") != names.end();
  dw.tableLayers(static_cast<int>(names.size() + (has_zero ? 0 : 1)));
  if (!has_zero)
    dxf.writeLayer(dw, DL_LayerData("0", 0), DL_Attributes("", 7, -1, -1, "CONTINUOUS"));
  for (size_t i = 0; i < layers.size(); ++i) {
    const int rgb = true_colour ? static_cast<int>(layers[i].rgb) : -1;
    dxf.writeLayer(dw, DL_LayerData(names[i], 0),
                   DL_Attributes("", NearestAciColour(layers[i].rgb), rgb, -1, "CONTINUOUS"));
  }
  dw.tableEnd();
  // dxflib's DIMSTYLE refers to the handle of a text style named exactly "Standard".
  dw.tableStyle(1);
  dxf.writeStyle(dw, DL_StyleData("Standard", 0, 0.0, 1.0, 0.0, 0, 2.5, "txt", ""));
  dw.tableEnd();
  dxf.writeView(dw);
  dxf.writeUcs(dw);
  dw.tableAppid(1);
  dxf.writeAppid(dw, "ACAD");
  dw.tableEnd();
  dxf.writeDimStyle(dw, 1, 1, 1, 1, 1);
  dxf.writeBlockRecord(dw);  // *Model_Space, *Paper_Space, *Paper_Space0
  dw.tableEnd();
  dw.sectionEnd();
}

void WriteBlocks(DL_Dxf& dxf, DL_WriterA& dw) {
  dw.sectionBlocks();
  for (const char* name : {"*Model_Space", "*Paper_Space", "*Paper_Space0"}) {
    dxf.writeBlock(dw, DL_BlockData(name, 0, 0.0, 0.0, 0.0));
    dxf.writeEndBlock(dw, name);
  }
  dw.sectionEnd();
}

void WriteEntities(const std::vector<DxfLayerLines>& layers, const std::vector<std::string>& names,
                   DL_Dxf& dxf, DL_WriterA& dw) {
  dw.sectionEntities();
  for (size_t i = 0; i < layers.size(); ++i) {
    const DL_Attributes by_layer(names[i], 256, -1, -1, "BYLAYER");
    for (const Polyline2& line : layers[i].lines) {
      if (line.points.size() < 2) continue;
      const int n = static_cast<int>(line.points.size());
      dxf.writePolyline(dw, DL_PolylineData(n, 0, 0, line.closed ? 1 : 0), by_layer);
      for (const Eigen::Vector2d& p : line.points) {
        dxf.writeVertex(dw, DL_VertexData(p.x(), p.y(), 0.0, 0.0));
      }
      dxf.writePolylineEnd(dw);
    }
  }
  dw.sectionEnd();
}

// DL_WriterA reports no write errors, but its stream writes nothing once a write has failed: the
// file is whole exactly when it ends with the EOF record, the last thing written.
void CheckComplete(const std::string& temp_path, const std::string& path) {
  static const std::string kEnd = "  0\nEOF\n";
  std::ifstream in(temp_path, std::ios::binary | std::ios::ate);
  const std::streamoff size = in ? static_cast<std::streamoff>(in.tellg()) : -1;
  std::string tail(kEnd.size(), '\0');
  if (size >= static_cast<std::streamoff>(kEnd.size())) {
    in.seekg(size - static_cast<std::streamoff>(kEnd.size()));
    in.read(&tail[0], static_cast<std::streamsize>(tail.size()));
  }
  if (!in || tail != kEnd) {
    throw InputError(path, "",
                     "the DXF writer could not write the whole file (disk full, file size limit "
                     "or I/O error); the destination is unchanged");
  }
}

}  // namespace

void DxfWriteOptions::Check() const {}

std::vector<std::string> DxfLayerNames(const std::vector<DxfLayerLines>& layers) {
  std::vector<std::string> names;
  std::set<std::string> taken;  // upper case: AutoCAD compares names ignoring case
  for (const DxfLayerLines& layer : layers) {
    std::string name = LayerName(layer.name, "");
    for (int k = 2; !taken.insert(UpperAscii(name)).second; ++k) {
      name = LayerName(layer.name, "_" + std::to_string(k));
    }
    names.push_back(name);
  }
  return names;
}

int NearestAciColour(uint32_t rgb) {
  CANDI_CHECK(rgb <= 0xffffffu) << "rgb = 0x" << std::hex << rgb << "; must be <= 0xffffff";
  if (rgb == 0) return 7;
  const auto channel = [](uint32_t c, int shift) { return static_cast<int>((c >> shift) & 0xff); };
  int best = 1;
  int best_distance = 1 << 30;
  for (int aci = 1; aci < 256; ++aci) {
    int distance = 0;
    for (int shift : {16, 8, 0}) {
      const int d = channel(rgb, shift) - channel(AciPalette()[aci], shift);
      distance += d * d;
    }
    if (distance < best_distance) best = aci, best_distance = distance;
  }
  return best;
}

uint32_t AciColourRgb(int aci) {
  CANDI_CHECK(aci >= 1 && aci <= 255) << "aci = " << aci << "; must be in 1-255";
  return AciPalette()[aci];
}

namespace {

// Writes the drawing to `file`'s temporary (dxflib opens the file by name itself); `path` names it
// in messages.
void WriteDxfTo(const DxfWriteOptions& options, const std::vector<DxfLayerLines>& layers, const std::string& path,
                const AtomicFile& file) {
  options.Check();
  size_t polylines = 0;
  Eigen::AlignedBox2d extent;
  for (const DxfLayerLines& layer : layers) {
    CheckLayer(layer);
    for (const Polyline2& line : layer.lines) {
      if (line.points.size() < 2) continue;
      ++polylines;
      for (const Eigen::Vector2d& p : line.points) extent.extend(p);
    }
  }
  // Handles are written through dxflib's int.
  CANDI_CHECK(layers.size() + polylines < 0x7fff0000u)
      << layers.size() << " layers and " << polylines << " polylines: too many DXF handles";
  const unsigned long handle_seed =
      std::max<unsigned long>(0xffff, 0x30 + kOtherHandles + layers.size() + polylines);
  const std::vector<std::string> names = DxfLayerNames(layers);
  for (size_t i = 0; i < layers.size(); ++i) {
    if (names[i] != layers[i].name) {
      LogWarning(path + ": layer '" + layers[i].name + "' is written as '" + names[i] + "'");
    }
  }

  {
    DL_Dxf dxf;
    std::unique_ptr<DL_WriterA> dw(dxf.out(file.temp_path().c_str(), DL_Codes::AC1015));
    if (!dw) throw InputError(path, "", "cannot open " + file.temp_path() + " for writing");
    WriteHeader(options, extent, handle_seed, *dw);
    WriteTables(layers, names, options.true_colour, dxf, *dw);
    WriteBlocks(dxf, *dw);
    WriteEntities(layers, names, dxf, *dw);
    dxf.writeObjects(*dw);
    dxf.writeObjectsEnd(*dw);
    dw->dxfEOF();
    CANDI_CHECK(dw->getNextHandle() <= handle_seed)
        << "dxflib used handles up to " << dw->getNextHandle() << ", past $HANDSEED "
        << handle_seed;
    dw->close();
  }
  CheckComplete(file.temp_path(), path);
}

}  // namespace

void WriteSectionDxf(const DxfWriteOptions& options, const std::vector<DxfLayerLines>& layers,
                     const std::string& path) {
  // AtomicFile renames its temporary over `path` once the drawing is known to be complete (or
  // removes it on any exception).
  AtomicFile file(path);
  WriteDxfTo(options, layers, path, file);
  file.Commit();
}

std::string SectionDxfText(const DxfWriteOptions& options, const std::vector<DxfLayerLines>& layers) {
  // dxflib writes files only: the drawing goes to an AtomicFile's temporary (removed on an
  // interrupt, and when `file` goes out of scope uncommitted), and is read back.
  static std::atomic<uint64_t> serial{0};
  const std::string name = (std::filesystem::temp_directory_path() /
                            ("candi-section-" + std::to_string(getpid()) + "-" + std::to_string(serial++) + ".dxf"))
                               .string();
  const AtomicFile file(name);
  WriteDxfTo(options, layers, "section.dxf", file);
  return ReadFileToString(file.temp_path());
}

}  // namespace candi::section
