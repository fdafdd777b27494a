// Diagnostics: levelled log lines on stderr, one line per call, safe from
// any thread. (Run logs, the recorded runs, are server/sim/log/.)
// Tests install a sink to fail on warnings (see tests/support/no_warnings.h).
#pragma once

#include <functional>
#include <sstream>
#include <string_view>

namespace sim4cv::diagnostics {

enum class Level { kDebug = 0, kInfo = 1, kWarning = 2, kError = 3 };

// Lines below this level are not written. Default: kInfo.
void SetMinLevel(Level level);

// Replaces where lines go (default: stderr). An empty function restores stderr.
void SetSink(std::function<void(Level, std::string_view)> sink);

void Write(Level level, std::string_view text);

const char* LevelName(Level level);

}  // namespace sim4cv::diagnostics

#define SIM4CV_LOG(level, stream_expr)                          \
  do {                                                          \
    std::ostringstream sim4cv_log_stream;                       \
    sim4cv_log_stream << stream_expr;                           \
    ::sim4cv::diagnostics::Write(level, sim4cv_log_stream.str());       \
  } while (0)
#define LOG_DEBUG(x) SIM4CV_LOG(::sim4cv::diagnostics::Level::kDebug, x)
#define LOG_INFO(x) SIM4CV_LOG(::sim4cv::diagnostics::Level::kInfo, x)
#define LOG_WARNING(x) SIM4CV_LOG(::sim4cv::diagnostics::Level::kWarning, x)
#define LOG_ERROR(x) SIM4CV_LOG(::sim4cv::diagnostics::Level::kError, x)
