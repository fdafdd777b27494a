// C++ helpers over protocol/shm_layout.h shared by the daemon and the C++
// client: atomic access to the plain fields, the cross-process futex calls,
// the geometry of the frame object and of a client's area, the socket
// address, and typed accessors that compute every address from a geometry
// the caller holds itself, never from fields read back out of shared memory
// (which another process may have changed). The rules they implement are in
// docs/protocol.md section 13.
#pragma once

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <ctime>
#include <string>

// Relative to this file, so the headers work in the source tree and installed
// (PREFIX/include/sim4cv/protocol/) alike.
#include "channels.h"
#include "shm_layout.h"

namespace sim4cv::shm {

static_assert(std::atomic_ref<uint64_t>::is_always_lock_free && std::atomic_ref<uint32_t>::is_always_lock_free,
              "shared-memory fields need lock-free (address-free) atomics");

// Atomic access to a field of the mapped layout.
template <typename T>
std::atomic_ref<T> Atomic(T& field) {
  return std::atomic_ref<T>(field);
}

// FUTEX_WAIT without FUTEX_PRIVATE_FLAG: the word is shared between
// processes. Returns when woken, at once if `word` != `expected`, on a signal,
// or after `timeout_ns` (negative: no limit). Callers re-check their condition.
inline void FutexWait(uint32_t& word, uint32_t expected, int64_t timeout_ns) {
  timespec timeout{static_cast<time_t>(timeout_ns / 1'000'000'000), static_cast<long>(timeout_ns % 1'000'000'000)};
  syscall(SYS_futex, &word, FUTEX_WAIT, expected, timeout_ns < 0 ? nullptr : &timeout, nullptr, 0);
}

// Wakes up to `count` processes waiting on `word`.
inline void FutexWake(uint32_t& word, int count) { syscall(SYS_futex, &word, FUTEX_WAKE, count, nullptr, nullptr, 0); }

// Bumps a futex word the caller alone writes (its own count, never read back)
// and wakes every waiter. Waking unconditionally costs one system call but
// trusts no waiter count that another process could have zeroed.
inline void StoreAndWake(uint32_t& word, uint32_t value) {
  Atomic(word).store(value, std::memory_order_seq_cst);
  FutexWake(word, 0x7fffffff);
}

// The Unix socket a daemon serving --shm-name NAME ("/name") listens on: in
// the abstract namespace (no file; it disappears with the daemon), this
// prefix then NAME. sockaddr_un.sun_path holds it from its first byte, a NUL.
inline constexpr char kShmSocketPrefix[] = "sim4cv-shm";
// The longest NAME (with its '/') that fits in sun_path (108 bytes).
inline constexpr std::size_t kShmMaxNameBytes = 107 - (sizeof kShmSocketPrefix - 1);
inline std::string SocketPath(const std::string& name) { return std::string(1, '\0') + kShmSocketPrefix + name; }

constexpr uint64_t AlignUp(uint64_t value, uint64_t alignment) {
  return (value + alignment - 1) / alignment * alignment;
}

// Where everything lives in the frame object with the given parameters. A
// slot holds only the planes of `channel_mask` (bit 1 << proto Channel),
// packed in the order of the channel table (protocol/channels.h): smaller
// slots are less to copy past and more of them stay in cache.
struct Geometry {
  // Per entry of channels::kPixelChannels: the plane's offset within a slot; 0: not carried.
  std::array<uint64_t, channels::kPixelChannelCount> offsets{};
  uint64_t slot_bytes = 0;
  uint32_t slot_count = 0;
  uint64_t slots_offset = 0;
  uint64_t total_bytes = 0;
};

inline Geometry ComputeGeometry(uint32_t width, uint32_t height, uint32_t slot_count,
                                channels::ChannelSet channel_mask = channels::kAllPixels) {
  const uint64_t pixels = static_cast<uint64_t>(width) * height;
  uint64_t end = kShmFrameHeaderBytes;
  Geometry g;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    const channels::ChannelInfo& info = channels::kPixelChannels[i];
    if (!channels::Has(channel_mask, info.id)) continue;
    g.offsets[i] = AlignUp(end, kShmAlignment);
    end = g.offsets[i] + pixels * info.bytes_per_pixel;
  }
  g.slot_bytes = AlignUp(end, 4096);
  g.slot_count = slot_count;
  g.slots_offset = 4096;
  g.total_bytes = g.slots_offset + g.slot_bytes * slot_count;
  return g;
}

// A client's area: the same for every client and every daemon of this layout version.
inline constexpr uint64_t kAreaRequestOffset = kShmAreaHeaderBytes;
inline constexpr uint64_t kAreaResponseOffset =
    kAreaRequestOffset + static_cast<uint64_t>(kShmRequestCapacity) * kShmRequestSlotBytes;
inline constexpr uint64_t kAreaBytes =
    AlignUp(kAreaResponseOffset + static_cast<uint64_t>(kShmResponseDepth) * kShmResponseMessageBytes, 4096);

// Response k's sequence word while it is written and once it is complete.
constexpr uint64_t ResponseWritingSequence(uint64_t k) { return 2 * k + 1; }
constexpr uint64_t ResponseCompleteSequence(uint64_t k) { return 2 * k + 2; }

// Typed access to a mapped frame object, by a geometry the holder computed
// or validated itself.
class FrameMap {
 public:
  FrameMap() = default;
  FrameMap(void* base, const Geometry& geometry) : base_(static_cast<uint8_t*>(base)), geometry_(geometry) {}

  uint8_t* base() const { return base_; }
  const Geometry& geometry() const { return geometry_; }
  ShmHeader& header() const { return *reinterpret_cast<ShmHeader*>(base_); }
  // Slot `publication - 1`'s bytes for any publication number: always inside the object.
  uint8_t* slot_bytes(uint64_t slot) const {
    return base_ + geometry_.slots_offset + (slot % geometry_.slot_count) * geometry_.slot_bytes;
  }
  ShmFrameHeader& slot(uint64_t slot) const { return *reinterpret_cast<ShmFrameHeader*>(slot_bytes(slot)); }

 private:
  uint8_t* base_ = nullptr;
  Geometry geometry_;
};

// Typed access to a mapped client area (its geometry is fixed: kAreaBytes).
class AreaMap {
 public:
  AreaMap() = default;
  explicit AreaMap(void* base) : base_(static_cast<uint8_t*>(base)) {}

  uint8_t* base() const { return base_; }
  ShmAreaHeader& header() const { return *reinterpret_cast<ShmAreaHeader*>(base_); }
  ShmRequestSlot& request(uint64_t n) const {
    return reinterpret_cast<ShmRequestSlot*>(base_ + kAreaRequestOffset)[n % kShmRequestCapacity];
  }
  ShmResponseMessage& response(uint64_t k) const {
    return reinterpret_cast<ShmResponseMessage*>(base_ + kAreaResponseOffset)[k % kShmResponseDepth];
  }

 private:
  uint8_t* base_ = nullptr;
};

}  // namespace sim4cv::shm
