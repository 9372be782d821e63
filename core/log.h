// Logging hook for the libraries.
//
// core/ depends on no logging library; it reports through a sink that the application sets
// (apps/ routes it to spdlog). The default sink writes "[level] message" to stderr.
// Thread-safe: the sink is called under a mutex.
#pragma once

#include <functional>
#include <string>

namespace candi {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };

using LogSink = std::function<void(LogLevel, const std::string&)>;

// Replaces the sink (nullptr restores the default). Returns the previous one.
LogSink SetLogSink(LogSink sink);
void Log(LogLevel level, const std::string& message);
inline void LogInfo(const std::string& message) { Log(LogLevel::kInfo, message); }
inline void LogWarning(const std::string& message) { Log(LogLevel::kWarning, message); }
inline void LogDebug(const std::string& message) { Log(LogLevel::kDebug, message); }

}  // namespace candi
