#include "server/common/diagnostics.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <string>

#include "server/common/check.h"

namespace sim4cv::diagnostics {
namespace {
std::atomic<int> g_min_level{static_cast<int>(Level::kInfo)};
std::mutex g_mutex;
std::function<void(Level, std::string_view)> g_sink;
}  // namespace

void SetMinLevel(Level level) { g_min_level = static_cast<int>(level); }

void SetSink(std::function<void(Level, std::string_view)> sink) {
  std::lock_guard lock(g_mutex);
  g_sink = std::move(sink);
}

const char* LevelName(Level level) {
  switch (level) {
    case Level::kDebug: return "DEBUG";
    case Level::kInfo: return "INFO";
    case Level::kWarning: return "WARN";
    case Level::kError: return "ERROR";
  }
  return "?";
}

void Write(Level level, std::string_view text) {
  if (static_cast<int>(level) < g_min_level) return;
  std::lock_guard lock(g_mutex);
  if (g_sink) {
    g_sink(level, text);
    return;
  }
  const double t = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  std::fprintf(stderr, "[%.6f] %-5s %.*s\n", t, LevelName(level), static_cast<int>(text.size()), text.data());
}

}  // namespace sim4cv::diagnostics

namespace sim4cv::detail {
void AbortOnBrokenInvariant(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "sim4cv: broken invariant `%s` at %s:%d\n", condition, file, line);
  std::abort();
}
}  // namespace sim4cv::detail
