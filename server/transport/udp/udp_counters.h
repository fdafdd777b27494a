// The UDP transport's counters. Its thread counts into plain integers and
// adds them to the shared session::Counters once per loop turn (and before
// answering GetStats), so a flood of datagrams costs no lock per datagram.
// Names are documented in docs/protocol.md section 12.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "server/session/counters.h"

namespace sim4cv::transport {

enum class UdpCounter : std::size_t {
  kDatagramsReceived,
  kDatagramsTruncated,
  kReceiveBufferOverflow,
  kMalformed,
  kUnregisteredSender,
  kClientFrameChunk,
  kOutOfOrder,
  kRegistrations,
  kExpired,
  kClosedByError,
  kTooManyClients,
  kErrorsSent,
  kRepliesRateLimited,
  kSendFailed,
  kFramesSent,
  kChunksSent,
  kConfigureRepeated,
  kCount,
};

class UdpCounters {
 public:
  void Add(UdpCounter counter, uint64_t amount = 1) { pending_[static_cast<std::size_t>(counter)] += amount; }

  // Moves what was counted since the last flush into `shared`.
  void Flush(session::Counters& shared) {
    static const std::array<std::string, kCount> kNames = {
        "udp.datagrams_received", "udp.datagrams_truncated", "udp.receive_buffer_overflow",
        "udp.malformed",          "udp.unregistered_sender", "udp.client_frame_chunk",
        "udp.out_of_order",       "udp.registrations",       "udp.expired",
        "udp.closed_by_error",    "udp.too_many_clients",    "udp.errors_sent",
        "udp.replies_rate_limited", "udp.send_failed",       "udp.frames_sent",
        "udp.chunks_sent",        "udp.configure_repeated"};
    for (std::size_t i = 0; i < kCount; ++i) {
      if (pending_[i] == 0) continue;
      shared.Add(kNames[i], pending_[i]);
      totals_[i] += pending_[i];
      pending_[i] = 0;
    }
  }

  // Everything counted and flushed so far.
  uint64_t total(UdpCounter counter) const { return totals_[static_cast<std::size_t>(counter)]; }

 private:
  static constexpr std::size_t kCount = static_cast<std::size_t>(UdpCounter::kCount);
  std::array<uint64_t, kCount> pending_{};
  std::array<uint64_t, kCount> totals_{};
};

}  // namespace sim4cv::transport
