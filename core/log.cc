#include "core/log.h"

#include <cstdio>
#include <mutex>

namespace candi {

namespace {
std::mutex& Mutex() {
  static std::mutex mutex;
  return mutex;
}
LogSink& Sink() {
  static LogSink sink;
  return sink;
}
const char* LevelName(LogLevel level) {
  switch (level) {
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarning: return "warning";
    case LogLevel::kError: return "error";
  }
  return "?";
}
}  // namespace

LogSink SetLogSink(LogSink sink) {
  std::lock_guard<std::mutex> lock(Mutex());
  LogSink previous = std::move(Sink());
  Sink() = std::move(sink);
  return previous;
}

void Log(LogLevel level, const std::string& message) {
  std::lock_guard<std::mutex> lock(Mutex());
  if (Sink()) {
    Sink()(level, message);
  } else if (level >= LogLevel::kInfo) {
    std::fprintf(stderr, "[%s] %s\n", LevelName(level), message.c_str());
  }
}

}  // namespace candi
