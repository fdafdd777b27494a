// A token bucket: at most `burst` events at once and `per_second` on
// average. The UDP transport uses it so that no stream of datagrams, however
// fast, makes the daemon send a comparable stream of replies.
#pragma once

#include <algorithm>
#include <chrono>

namespace sim4cv::transport {

class RateLimiter {
 public:
  using Clock = std::chrono::steady_clock;

  RateLimiter(double per_second, double burst) : per_second_(per_second), burst_(burst), tokens_(burst) {}

  // True (and one token spent) if an event may happen at `now`.
  bool Allow(Clock::time_point now) {
    const double elapsed = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    if (elapsed > 0) tokens_ = std::min(burst_, tokens_ + elapsed * per_second_);
    if (tokens_ < 1) return false;
    tokens_ -= 1;
    return true;
  }

 private:
  double per_second_;
  double burst_;
  double tokens_;
  Clock::time_point last_{};
};

}  // namespace sim4cv::transport
