// Three tiers of checks, after Drake's DRAKE_DEMAND / DRAKE_THROW_UNLESS /
// DRAKE_ASSERT:
//   SIM4CV_DEMAND(cond)            a broken internal invariant: log and abort.
//   SIM4CV_THROW_UNLESS(cond, msg) bad input from a user or peer: throw
//                                  std::invalid_argument naming the value.
//   SIM4CV_ASSERT(cond)            a costly invariant check, debug builds only.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace sim4cv::detail {
[[noreturn]] void AbortOnBrokenInvariant(const char* condition, const char* file, int line);
}  // namespace sim4cv::detail

#define SIM4CV_DEMAND(condition)                                                   \
  do {                                                                             \
    if (!(condition)) ::sim4cv::detail::AbortOnBrokenInvariant(#condition, __FILE__, __LINE__); \
  } while (0)

// `message` is a stream expression, e.g. "width " << w << " must be > 0".
#define SIM4CV_THROW_UNLESS(condition, message)                    \
  do {                                                             \
    if (!(condition)) {                                            \
      std::ostringstream sim4cv_check_stream;                      \
      sim4cv_check_stream << message;                              \
      throw std::invalid_argument(sim4cv_check_stream.str());      \
    }                                                              \
  } while (0)

#ifdef NDEBUG
#define SIM4CV_ASSERT(condition) \
  do {                           \
  } while (0)
#else
#define SIM4CV_ASSERT(condition) SIM4CV_DEMAND(condition)
#endif
