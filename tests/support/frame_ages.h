// How old frames are when a test's reader has them: render end
// (Frame.render_end_mono_ns, CLOCK_MONOTONIC, which steady_clock reads on
// Linux) to now, in milliseconds, collected and summarised the same way for
// every transport (docs/protocol.md 7.3).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

namespace sim4cv::testing {

inline int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

class FrameAges {
 public:
  // A frame rendered at `render_end_ns` is in hand now.
  void Add(int64_t render_end_ns) { ages_ms_.push_back(static_cast<double>(MonotonicNs() - render_end_ns) / 1e6); }
  // The frame at fraction `p` (0..1) of the ages sorted: 0.5 the median
  // (the upper one of an even count), 1 the worst.
  double Percentile(double p) const {
    std::vector<double> sorted = ages_ms_;
    std::sort(sorted.begin(), sorted.end());
    return sorted[std::min(sorted.size() - 1, static_cast<std::size_t>(p * static_cast<double>(sorted.size())))];
  }
  // "[ numbers  ] WHAT: median M ms, 90% N ms, worst W ms" on stdout.
  void Print(const std::string& what) const {
    std::cout << "[ numbers  ] " << what << ": median " << Percentile(0.5) << " ms, 90% " << Percentile(0.9)
              << " ms, worst " << Percentile(1.0) << " ms\n";
  }

 private:
  std::vector<double> ages_ms_;
};

}  // namespace sim4cv::testing
