// Order statistics for benchmark samples.
#pragma once

#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstddef>
#include <vector>

namespace sim4cv::bench {

// CLOCK_MONOTONIC in nanoseconds: the clock Frame.render_end_mono_ns uses.
inline int64_t MonotonicNanoseconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

struct Summary {
  double median = 0, p99 = 0, max = 0, mean = 0;
};

inline Summary Summarize(std::vector<double> samples) {
  Summary s;
  if (samples.empty()) return s;
  std::sort(samples.begin(), samples.end());
  auto at = [&](double q) { return samples[std::min(samples.size() - 1, static_cast<std::size_t>(q * (samples.size() - 1) + 0.5))]; };
  s.median = at(0.5);
  s.p99 = at(0.99);
  s.max = samples.back();
  for (double x : samples) s.mean += x;
  s.mean /= static_cast<double>(samples.size());
  return s;
}

}  // namespace sim4cv::bench
