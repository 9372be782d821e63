// The point-file formats and how a file's format is found: by its extension, confirmed by its
// first bytes. A mismatch and DXF (a drawing, not a point file) are errors, never guesses.
#pragma once

#include <string>

namespace candi::io {

enum class PointFormat { kPly, kLas, kXyz, kPts, kE57 };
std::string PointFormatName(PointFormat format);  // "PLY", "LAS", "XYZ", "PTS", "E57"

// Format from the extension (.ply, .las, .xyz/.txt/.asc/.csv, .pts, .e57), confirmed by the first
// bytes (E57: the "ASTM-E57" signature).
// .laz reads as kLas (LAZ content). Throws InputError for .dxf (a drawing, not a point file),
// unknown extensions, and content that contradicts the extension.
PointFormat DetectPointFormat(const std::string& path);
// Format from the extension only, for outputs (.laz: kLas, which the LAS writer compresses).
// Throws InputError for unknown extensions.
PointFormat OutputPointFormat(const std::string& path);

}  // namespace candi::io
