// When a TCP connection has waited too long (docs/reliability.md, finding 13): a Hello
// must arrive complete within --handshake-timeout-ms of connecting, a message
// that has started must end within --message-timeout-ms, and, if
// --idle-timeout-ms is set, a handshaken connection must not go that long
// without a byte either way. Pure bookkeeping on time points; the session
// owns the timer and asks here what is due. 0 turns a timeout off.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>

#include "sim4cv.pb.h"

namespace sim4cv::transport {

struct TcpTimeouts {
  uint32_t handshake_ms;
  uint32_t message_ms;
  uint32_t idle_ms;
};

class ConnectionDeadlines {
 public:
  using Clock = std::chrono::steady_clock;

  // What expired: the fatal Error to send.
  struct Expired {
    proto::ErrorCode code;
    std::string message;
  };

  ConnectionDeadlines(const TcpTimeouts& timeouts, Clock::time_point connected);

  void Handshaken() { handshaken_ = true; }
  // Bytes arrived or left (the idle clock).
  void Active(Clock::time_point now) { last_active_ = now; }
  // The first byte of a message arrived / its last byte did.
  void MessageStarted(Clock::time_point now) { message_started_ = now; }
  void MessageEnded() { message_started_.reset(); }

  // The earliest moment something may expire; Clock::time_point::max() if none.
  Clock::time_point next() const;
  // What has expired at `now`, if anything.
  std::optional<Expired> Check(Clock::time_point now) const;

 private:
  static Clock::time_point After(Clock::time_point from, uint32_t ms);

  TcpTimeouts timeouts_;
  Clock::time_point connected_;
  Clock::time_point last_active_;
  std::optional<Clock::time_point> message_started_;
  bool handshaken_ = false;
};

}  // namespace sim4cv::transport
