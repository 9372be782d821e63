// DXF export (dxflib) of section lines: one DXF layer per section, each polyline one LWPOLYLINE.
//
// File: ASCII DXF, AutoCAD 2000 (AC1015), written by dxflib's DL_Dxf/DL_WriterA: an optional 999
// comment first, then HEADER ($ACADVER AC1015, $DWGCODEPAGE ANSI_1252, $HANDSEED, $INSUNITS 6 =
// metres, $MEASUREMENT 1 = metric, $EXTMIN/$EXTMAX = the lines' extent), TABLES (VPORT, LTYPE,
// LAYER, STYLE, VIEW, UCS, APPID, DIMSTYLE, BLOCK_RECORD), BLOCKS (*Model_Space, *Paper_Space,
// *Paper_Space0), ENTITIES, OBJECTS. The LAYER table always holds layer "0" and one entry per
// DxfLayerLines, also for layers without lines (so that an empty section is still labelled).
// Entities take colour and linetype BYLAYER. The stored view is dxflib's fixed one: CAD programs
// may open away from lines at survey coordinates until "zoom extents".
//
// Precision: dxflib writes every coordinate as "%.16f" with trailing zeros cut, so a value comes
// back within 1e-16 m of the double given, and bit-identical for |value| >= 0.5 m: survey
// coordinates of 10^6-10^7 m keep their full double precision (~1e-9 m), far below a millimetre.
//
// Text (layer names, the comment) is encoded as AutoCAD and ezdxf write DXF before 2007: ASCII and
// Latin-1 characters as their ANSI_1252 byte, other characters as \U+XXXX escapes (AutoCAD
// decodes them; GDAL 3.6, ezdxf's default loader and candi's ReadDxf keep them as written).
//
// Atomic: the drawing goes to a temporary file beside `path` (core/atomic_file.h), which replaces
// `path` only once it is complete; on any failure `path` is left as it was and no temporary stays.
// Thread-safe for distinct paths.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/polyline.h"

namespace candi::section {

struct DxfLayerLines {
  // The layer name, UTF-8. Written as DxfLayerNames() gives it: characters AutoCAD refuses in
  // names (< > / \ " : ; ? * | , = ` and control characters), invalid UTF-8 and characters beyond
  // U+FFFF become '_', the rest is encoded as the file comment says; at most 255 characters (and
  // 1000 bytes: dxflib's readers cut longer lines); an empty name is the default layer "0"; names
  // equal ignoring ASCII case (as AutoCAD compares them) after this get "_2", "_3", ... appended.
  std::string name;
  // 0xRRGGBB, <= 0xffffff: the layer colour, written as the nearest ACI colour (group 62; black
  // becomes 7, which CAD shows black on white and white on black) and, with
  // DxfWriteOptions::true_colour, exactly (group 420).
  uint32_t rgb = 0xffffff;
  // Drawing coordinates, m: finite, |x|, |y| <= 1e12 (survey coordinates of 1e6-1e7 m are fine).
  // Polylines with fewer than 2 points are skipped; closed ones get the LWPOLYLINE closed flag.
  std::vector<Polyline2> lines;
};

struct DxfWriteOptions {
  // Provenance (UTF-8), written as a 999 comment at the top; "" writes none. Control characters
  // (newlines, tabs) become spaces, the rest is encoded as the file comment says; cut at 1000
  // bytes (one line a dxflib reader can hold).
  std::string comment;
  // Also write each layer's exact rgb as true colour (group 420). True colour came with DXF 2004
  // (AC1018) and AC1015 does not define it: readers that know it honour it (GDAL 3.6 does,
  // checked), AutoCAD 2000-era readers ignore or may refuse it. Off: the ACI colour only.
  bool true_colour = false;
  void Check() const;  // every value is valid; kept for the options convention
};

// The layer names WriteSectionDxf writes for `layers`, in the same order (see
// DxfLayerLines::name): ANSI_1252 text, distinct ignoring ASCII case.
std::vector<std::string> DxfLayerNames(const std::vector<DxfLayerLines>& layers);

// The AutoCAD Color Index colour nearest `rgb` (0xRRGGBB; Euclidean distance in RGB, the lower
// index on ties): 1-255; black (0x000000) gives 7. CANDI_CHECK: rgb <= 0xffffff.
int NearestAciColour(uint32_t rgb);
// The RGB (0xRRGGBB) of ACI colour `aci`, 1-255 (7 as white), AutoCAD's standard palette.
uint32_t AciColourRgb(int aci);

// Writes `layers` to `path` as described in the file comment.
// Misuse (CANDI_CHECK, before anything is written; the message names the layer, polyline and
// vertex): a non-finite coordinate or one beyond 1e12 m, rgb > 0xffffff, a polyline of 2^31 or
// more vertices.
// Throws InputError naming the path when it cannot be written (missing or read-only folder, path
// a folder, disk full or file size limit: the writer's output is checked to be complete); the
// destination is then unchanged.
void WriteSectionDxf(const DxfWriteOptions& options, const std::vector<DxfLayerLines>& layers,
                     const std::string& path);

// The same drawing as text (for a reply rather than a file). Misuse as WriteSectionDxf; throws
// InputError when the system's temporary folder cannot be written (dxflib writes files only).
std::string SectionDxfText(const DxfWriteOptions& options, const std::vector<DxfLayerLines>& layers);

}  // namespace candi::section
