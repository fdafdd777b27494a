// TCP adapter: length-prefixed Envelopes over a stream, one Asio thread for
// every connection (no per-client thread, no locks but the mailbox's).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "server/common/limits.h"
#include "server/transport/tcp/connection_deadlines.h"
#include "server/transport/transport.h"

namespace sim4cv::transport {

struct TcpOptions {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 0;  // 0: any free port
  uint32_t max_clients = 64;
  uint32_t max_message_bytes = limits::kDefaultMaxMessageBytes;
  // Kernel send buffer per connection. Small, so that a slow newest-frame
  // reader gets recent frames instead of a backlog queued in the kernel.
  uint32_t send_buffer_bytes = 256u << 10;
  TcpTimeouts timeouts = {limits::kDefaultHandshakeTimeoutMs, limits::kDefaultMessageTimeoutMs,
                          limits::kDefaultIdleTimeoutMs};
};

// Binds and listens at once (so the port is known); serves after Start.
// Throws std::runtime_error naming the address if the port cannot be bound,
// or naming both numbers if the descriptor limit (RLIMIT_NOFILE, raised
// towards its hard limit if needed) cannot hold max_clients connections plus
// limits::kReservedDescriptors.
std::unique_ptr<Transport> MakeTcpTransport(const TcpOptions& options);

}  // namespace sim4cv::transport
