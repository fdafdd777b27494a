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

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <ctime>
#include <string>

#include "protocol/shm_layout.h"

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

// Bit of a pixel channel (kShmChannelRgb ...) in a channel mask.
constexpr uint32_t ChannelBit(uint32_t channel) { return 1u << channel; }

// The daemon flag's name of a pixel channel (--shm-channels rgb,depth,mask); "" for others.
constexpr const char* ChannelFlagName(uint32_t channel) {
  return channel == kShmChannelRgb     ? "rgb"
         : channel == kShmChannelDepth ? "depth"
         : channel == kShmChannelMask  ? "mask"
                                       : "";
}

// A channel mask as --shm-channels writes it, e.g. "rgb,mask".
inline std::string ChannelFlagValue(uint32_t channel_mask) {
  std::string value;
  for (uint32_t channel = kShmChannelRgb; channel <= kShmChannelMask; ++channel) {
    if ((channel_mask & ChannelBit(channel)) != 0)
      value.append(value.empty() ? "" : ",").append(ChannelFlagName(channel));
  }
  return value;
}

// Where everything lives in the frame object with the given parameters. A
// slot holds only the planes of `channel_mask`, packed in the order RGB,
// DEPTH, MASK: smaller slots are less to copy past and more of them stay in
// cache.
struct Geometry {
  uint64_t rgb_offset = 0, depth_offset = 0, mask_offset = 0;  // within a slot; 0: channel absent
  uint64_t slot_bytes = 0;
  uint32_t slot_count = 0;
  uint64_t slots_offset = 0;
  uint64_t total_bytes = 0;
};

inline Geometry ComputeGeometry(uint32_t width, uint32_t height, uint32_t slot_count,
                                uint32_t channel_mask = kShmAllPixelChannels) {
  const uint64_t pixels = static_cast<uint64_t>(width) * height;
  uint64_t end = kShmFrameHeaderBytes;
  auto place = [&](uint32_t channel, uint64_t bytes_per_pixel) -> uint64_t {
    if ((channel_mask & ChannelBit(channel)) == 0) return 0;
    const uint64_t offset = AlignUp(end, kShmAlignment);
    end = offset + pixels * bytes_per_pixel;
    return offset;
  };
  Geometry g;
  g.rgb_offset = place(kShmChannelRgb, 3);
  g.depth_offset = place(kShmChannelDepth, 4);
  g.mask_offset = place(kShmChannelMask, 2);
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
