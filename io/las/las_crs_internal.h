// The coordinate reference system a LAS/LAZ file states in its VLRs (ASPRS LAS 1.4 R15, 2.5:
// "LASF_Projection" records), and the VLR that states one for writing. Internal to io/las
// (las_reader.cc, las_writer.cc).
//
// Reading prefers OGC WKT (record 2112, the only form LAS 1.4 allows for formats 6-10) over
// GeoTIFF keys (records 34735-34737). GeoTIFF keys give "EPSG:n" from ProjectedCSTypeGeoKey
// (3072) or, without one, GeographicTypeGeoKey (2048), with "+v" for a VerticalCSTypeGeoKey
// (4096) code: the string PROJ takes. User-defined keys (32767) are not interpreted here (PROJ
// has no GeoTIFF-key parser); the result is empty and `note` says why. Pure parsing, no PROJ.
#pragma once

#include <string>
#include <vector>

#include "core/point_cloud.h"

namespace candi::io {

// The CRS stated by `vlrs` (in file order; VLRs and EVLRs), or "" with *note explaining what
// was found instead (may be null). Never throws: malformed records are skipped with a note.
std::string LasCrsOf(const std::vector<LasVlr>& vlrs, std::string* note = nullptr);

// True when `vlrs` hold a WKT or GeoTIFF-key projection record.
bool HasLasCrsRecord(const std::vector<LasVlr>& vlrs);

// A WKT projection VLR (user "LASF_Projection", record 2112, NUL-terminated) holding `wkt`.
LasVlr LasWktVlr(const std::string& wkt);

}  // namespace candi::io
