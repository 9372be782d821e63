#include "apps/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "core/log.h"

namespace candi::apps {

void SetupLogging(int verbosity) {
  auto logger = spdlog::stderr_color_mt("candi");
  logger->set_pattern("[%l] %v");
  logger->set_level(verbosity < 0 ? spdlog::level::warn
                    : verbosity == 0 ? spdlog::level::info : spdlog::level::debug);
  spdlog::set_default_logger(logger);
  SetLogSink([](LogLevel level, const std::string& message) {
    switch (level) {
      case LogLevel::kDebug: spdlog::debug(message); break;
      case LogLevel::kInfo: spdlog::info(message); break;
      case LogLevel::kWarning: spdlog::warn(message); break;
      case LogLevel::kError: spdlog::error(message); break;
    }
  });
}

}  // namespace candi::apps
