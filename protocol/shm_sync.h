// C++ helpers over protocol/shm_layout.h shared by the daemon and the C++
// client: atomic access to the plain fields, the cross-process futex calls,
// the reply checksum, the object's geometry and typed accessors. The rules
// they implement are in docs/protocol.md section 13.
#pragma once

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
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

// Bumps a futex word and wakes every waiter if `waiters` (or `sleeping`) says
// someone may be in FUTEX_WAIT. The seq_cst pair with the waiter's
// "announce, then re-read the word" means a wake-up is never lost.
inline void BumpAndWake(uint32_t& word, uint32_t& waiters) {
  Atomic(word).fetch_add(1, std::memory_order_seq_cst);
  if (Atomic(waiters).load(std::memory_order_seq_cst) != 0) FutexWake(word, 0x7fffffff);
}

// ShmReplySlot.state of a slot holding ticket `ticket`.
constexpr uint64_t ReplyWritingState(uint64_t ticket) { return 2 * ticket + 1; }
constexpr uint64_t ReplyCompleteState(uint64_t ticket) { return 2 * ticket + 2; }
constexpr uint64_t ReplyTicketOf(uint64_t state) { return (state - 1) / 2; }  // state != 0

// FNV-1a 32 over token (8 bytes LE), size (4 bytes LE) and data[0..size).
inline uint32_t ReplyChecksum(uint64_t token, const uint8_t* data, uint32_t size) {
  uint32_t hash = 2166136261u;
  auto mix = [&hash](uint8_t byte) { hash = (hash ^ byte) * 16777619u; };
  for (int i = 0; i < 8; ++i) mix(static_cast<uint8_t>(token >> (8 * i)));
  for (int i = 0; i < 4; ++i) mix(static_cast<uint8_t>(size >> (8 * i)));
  for (uint32_t i = 0; i < size; ++i) mix(data[i]);
  return hash;
}

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

// Where everything lives in an object with the given parameters. A slot holds
// only the planes of `channel_mask`, packed in the order RGB, DEPTH, MASK:
// smaller slots are less to copy past and more of them stay in cache.
struct Geometry {
  uint64_t rgb_offset = 0, depth_offset = 0, mask_offset = 0;  // within a slot; 0: channel absent
  uint64_t slot_bytes = 0;
  uint64_t slots_offset = 0, reply_offset = 0, response_offset = 0, response_entry_bytes = 0;
  uint64_t total_bytes = 0;
};

inline Geometry ComputeGeometry(uint32_t width, uint32_t height, uint32_t slot_count, uint32_t reply_capacity,
                                uint32_t response_entries, uint32_t channel_mask = kShmAllPixelChannels) {
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
  g.slots_offset = 4096;
  g.reply_offset = g.slots_offset + g.slot_bytes * slot_count;
  g.response_offset = g.reply_offset + static_cast<uint64_t>(kShmReplySlotBytes) * reply_capacity;
  g.response_entry_bytes =
      kShmResponseEntryHeaderBytes + static_cast<uint64_t>(kShmResponseDepth) * kShmResponseMessageBytes;
  g.total_bytes = AlignUp(g.response_offset + g.response_entry_bytes * response_entries, 4096);
  return g;
}

// Typed access to a mapped object whose header has been validated.
class Mapped {
 public:
  Mapped() = default;
  explicit Mapped(void* base) : base_(static_cast<uint8_t*>(base)) {}

  uint8_t* base() const { return base_; }
  ShmHeader& header() const { return *reinterpret_cast<ShmHeader*>(base_); }
  uint8_t* slot_bytes(uint64_t slot) const { return base_ + header().slots_offset + slot * header().slot_bytes; }
  ShmFrameHeader& slot(uint64_t slot) const { return *reinterpret_cast<ShmFrameHeader*>(slot_bytes(slot)); }
  ShmReplySlot& reply_slot(uint64_t ticket) const {
    return reinterpret_cast<ShmReplySlot*>(base_ + header().reply_offset)[ticket % header().reply_capacity];
  }
  ShmResponseEntry& response_entry(uint32_t entry) const {
    return *reinterpret_cast<ShmResponseEntry*>(base_ + header().response_offset +
                                                entry * header().response_entry_bytes);
  }
  ShmResponseMessage& response_message(uint32_t entry, uint64_t index) const {
    auto* first = reinterpret_cast<uint8_t*>(&response_entry(entry)) + kShmResponseEntryHeaderBytes;
    return reinterpret_cast<ShmResponseMessage*>(first)[index % header().response_depth];
  }

 private:
  uint8_t* base_ = nullptr;
};

}  // namespace sim4cv::shm
