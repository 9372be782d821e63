// Whether a LAS/LAZ file's 16-bit colour fields hold 16-bit colour (some high byte set) or 8-bit
// colour stored as is: only the data tells, and finding that 8-bit colours are 8-bit reads every
// record (for LAZ, decodes the whole file). A command opens a file several times (its bounds,
// then its points; a render's mode, then its points), so the answer is kept per process for the
// file as it is: its path, size and modification time. A file rewritten since is scanned again.
// Internal to io/las (las_reader.cc).
#pragma once

#include <functional>
#include <string>

namespace candi::io {

// scan() for `path` the first time (and whenever the file changed since), else its answer.
bool CachedWideColours(const std::string& path, const std::function<bool()>& scan);

}  // namespace candi::io
