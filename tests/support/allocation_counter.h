// Counts heap allocations, for tests of code that must not allocate once
// warm (the sim thread's and the encoders' steady state). It replaces the
// global operator new and delete, so include it from exactly one file of a
// test program.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

namespace sim4cv::testing::allocation_counter {
inline std::atomic<bool> counting{false};
inline std::atomic<std::size_t> allocations{0};
}  // namespace sim4cv::testing::allocation_counter

[[gnu::noinline]] void* operator new(std::size_t size) {
  if (sim4cv::testing::allocation_counter::counting) ++sim4cv::testing::allocation_counter::allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
// Not inlined, so that GCC does not see free() meet a pointer from operator new.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace sim4cv::testing {

// The number of heap allocations `body` makes.
template <typename Body>
std::size_t AllocationsIn(const Body& body) {
  allocation_counter::allocations = 0;
  allocation_counter::counting = true;
  body();
  allocation_counter::counting = false;
  return allocation_counter::allocations;
}

}  // namespace sim4cv::testing
