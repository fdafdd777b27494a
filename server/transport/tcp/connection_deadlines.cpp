#include "server/transport/tcp/connection_deadlines.h"

#include <algorithm>

namespace sim4cv::transport {

ConnectionDeadlines::ConnectionDeadlines(const TcpTimeouts& timeouts, Clock::time_point connected)
    : timeouts_(timeouts), connected_(connected), last_active_(connected) {}

ConnectionDeadlines::Clock::time_point ConnectionDeadlines::After(Clock::time_point from, uint32_t ms) {
  return ms == 0 ? Clock::time_point::max() : from + std::chrono::milliseconds(ms);
}

ConnectionDeadlines::Clock::time_point ConnectionDeadlines::next() const {
  Clock::time_point next = Clock::time_point::max();
  if (!handshaken_) next = std::min(next, After(connected_, timeouts_.handshake_ms));
  if (message_started_) next = std::min(next, After(*message_started_, timeouts_.message_ms));
  if (handshaken_ && !message_started_) next = std::min(next, After(last_active_, timeouts_.idle_ms));
  return next;
}

std::optional<ConnectionDeadlines::Expired> ConnectionDeadlines::Check(Clock::time_point now) const {
  if (!handshaken_ && now >= After(connected_, timeouts_.handshake_ms)) {
    return Expired{proto::ERROR_CODE_NOT_HANDSHAKEN,
                   "no complete Hello within " + std::to_string(timeouts_.handshake_ms) +
                       " ms of connecting (daemon flag --handshake-timeout-ms); send Hello as the first message"};
  }
  if (message_started_ && now >= After(*message_started_, timeouts_.message_ms)) {
    return Expired{proto::ERROR_CODE_INVALID_STATE,
                   "a message was started but not finished within " + std::to_string(timeouts_.message_ms) +
                       " ms (daemon flag --message-timeout-ms); send each length prefix and its envelope together"};
  }
  if (handshaken_ && !message_started_ && now >= After(last_active_, timeouts_.idle_ms)) {
    return Expired{proto::ERROR_CODE_INVALID_STATE,
                   "nothing received from or sent to this client for " + std::to_string(timeouts_.idle_ms) +
                       " ms (daemon flag --idle-timeout-ms); send a request (e.g. GetState) to stay connected"};
  }
  return std::nullopt;
}

}  // namespace sim4cv::transport
