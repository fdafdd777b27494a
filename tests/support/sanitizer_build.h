// Whether a process's RSS means anything in this build. Under AddressSanitizer
// it does not: the quarantine keeps freed memory mapped (up to 256 MiB by
// default) and the shadow grows with every allocation; nor under
// ThreadSanitizer, whose shadow and history memory grow with the daemon's
// threads and allocations (a baseline of 759 MiB). So the tests that bound
// the daemon's RSS check those bounds only without it (everything else they
// check still runs; docs/reliability.md, "Sanitizers").
#pragma once

namespace sim4cv {

#if defined(__SANITIZE_ADDRESS__) || defined(SIM4CV_TSAN_BUILD)  // the build defines the latter
inline constexpr bool kRssBoundsHold = false;
#else
inline constexpr bool kRssBoundsHold = true;
#endif

}  // namespace sim4cv
