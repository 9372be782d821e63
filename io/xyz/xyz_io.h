// XYZ and PTS text point files.
//
// Reading. XYZ: one point per line; values separated by blanks (runs count as one) or by one ','
// or ';' with optional blanks around it; CRLF accepted. Empty lines and lines starting with '#' or
// '//' are skipped; a first line with a non-numeric value (where the spec expects a number) is a
// header: skipped and logged. A first line that mixes ',' and ';' is an error (decimal commas are
// not supported). PTS (Leica): the first line is the point count (info().count); a line holding
// only an integer later starts a new section; a file without a count line is read as plain data.
// Columns follow PointReadOptions::columns ("x,y,z" required; "r,g,b" or "red,green,blue" 0-255
// integers; "nx,ny,nz"; "i"/"intensity" -> scalar "intensity"; "_"/"skip"; any other identifier
// -> a float scalar field); an invalid spec throws std::invalid_argument naming the entry. Without
// a spec the columns are guessed from the first data line and logged: 3 x,y,z; 4 x,y,z,i;
// 6 x,y,z,r,g,b when values 4-6 are integers in 0..255 (but not a unit vector like "0 0 1"), else
// x,y,z,nx,ny,nz; 7 x,y,z,i,r,g,b; 9 x,y,z,r,g,b,nx,ny,nz (colours first by the same test) or
// x,y,z,nx,ny,nz,r,g,b; otherwise x,y,z,c3,c4,... Extra values on a line are ignored (logged once).
// Positions are double (schema.position_type = kFloat64), parsed exactly (std::from_chars
// semantics); info().count is kUnknownCount (PTS: the count line) until the end, then the number
// read. If a shift sidecar exists (ReadShiftSidecar), the file holds local coordinates and
// info().frame is that shift; otherwise frame zero. The file is read in place (core/mapped_file.h):
// a Read() call's text is cut into blocks of about 1 MiB at line ends, parsed in parallel and
// taken in file order, so the points, the error (the first bad line) and the warnings (each
// once) are those of a reading line by line, on any number of threads. The Read() call that
// reaches a bad line throws; the points before it came in the earlier calls, as many as asked.
// InputError ("<path>: line N[, column K]: ...") for: an empty file (0 bytes), fewer values than
// the spec, non-finite or unparsable coordinates, unparsable normals or scalars, colours outside
// 0..255, lines over 1 MiB. A file of only comments (or only a header) has zero points.
//
// Writing. No header line for XYZ; PTS starts with the count (when the spec's count is unknown, a
// 20-character field patched in Close()). Columns: PointWriteOptions::columns, else
// x,y,z,[intensity],[r,g,b],[nx,ny,nz],[other scalars] (intensity first so that x,y,z,i,r,g,b
// reads back with the guess); alphas and layers are not written. Positions are in the spec's
// frame (chunks in other frames are re-expressed), written as the shortest round-trip double (or
// float with PositionPrecision::kFloat32, or kAuto with float positions and no shift), so a round
// trip is bit-exact; normals and float scalars as shortest floats, colours as integers. Close()
// commits the file atomically, then writes the shift sidecar when the frame is not zero (or
// removes a stale one). Without Close() the destination is untouched.
#pragma once

#include <memory>
#include <string>

#include "io/point_file.h"

namespace candi::io {

std::unique_ptr<PointReader> OpenXyzReader(const std::string& path, bool pts,
                                           const PointReadOptions& options);
std::unique_ptr<PointWriter> OpenXyzWriter(const std::string& path, bool pts,
                                           const PointWriteSpec& spec,
                                           const PointWriteOptions& options);

}  // namespace candi::io
