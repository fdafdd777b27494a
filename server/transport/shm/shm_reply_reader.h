// The daemon's end of the reply ring (clients -> daemon, many producers, one
// consumer): hands out complete messages in ticket order, counting what
// producers overwrote before it was read (shm.replies_dropped), slots a dead
// client reserved but never finished (shm.replies_abandoned) and messages
// that fail their checksum (shm.replies_corrupt).
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>

#include "server/session/counters.h"
#include "server/transport/shm/shm_region.h"

namespace sim4cv::transport {

class ShmReplyReader {
 public:
  using Clock = std::chrono::steady_clock;
  // A reserved slot still incomplete after this long is skipped.
  static constexpr std::chrono::milliseconds kAbandonAfter{200};

  struct Message {
    uint64_t token = 0;
    const uint8_t* data = nullptr;  // valid until the next call of Next
    uint32_t size = 0;
  };
  enum class Result {
    kMessage,  // `out` holds the next message
    kEmpty,    // nothing more was sent
    kStalled,  // the next ticket is reserved but not yet complete
  };

  // `spin` is how long Wait polls before it sleeps in FUTEX_WAIT.
  ShmReplyReader(std::shared_ptr<ShmRegion> region, session::Counters& counters, std::chrono::nanoseconds spin);

  Result Next(Message& out, Clock::time_point now);

  // The wake-up word; read it before draining, then pass it to Wait.
  uint32_t futex_value() const;
  // Returns once a client completes a reply after `seen` was read, on Wake,
  // or after `timeout`.
  void Wait(uint32_t seen, std::chrono::nanoseconds timeout);
  // Ends a Wait at once (shutdown).
  void Wake();

 private:
  void Drop(uint64_t count);

  std::shared_ptr<ShmRegion> region_;
  session::Counters& counters_;
  std::chrono::nanoseconds spin_;
  uint64_t read_ = 0;
  uint64_t stalled_ticket_ = UINT64_MAX;
  Clock::time_point stalled_since_;
  std::array<uint8_t, shm::kShmReplyDataBytes> buffer_{};
};

}  // namespace sim4cv::transport
