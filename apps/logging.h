// Routes candi's library log (core/log.h) to spdlog on stderr.
#pragma once

namespace candi::apps {
// verbosity: -1 warnings and errors only, 0 info, >= 1 debug.
void SetupLogging(int verbosity);
}  // namespace candi::apps
