// The shift sidecar "<path>.shift.json", written beside shifted PLY/XYZ/PTS outputs: the
// LocalFrame origin a file's coordinates are relative to (world = local + shift), with the size
// of the file it was written for, so that a sidecar left beside a rewritten file is ignored.
#pragma once

#include <optional>
#include <string>

#include "core/local_frame.h"

namespace candi::io {

std::string ShiftSidecarPath(const std::string& path);
void WriteShiftSidecar(const std::string& path, const LocalFrame& frame);
// Returns the sidecar's shift when it exists and was written for a file of the current size.
std::optional<LocalFrame> ReadShiftSidecar(const std::string& path);

}  // namespace candi::io
