// TCP adapter: length-prefixed Envelopes over a stream, one Asio thread for
// every connection (no per-client thread, no locks but the mailbox's).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "server/transport/transport.h"

namespace sim4cv::transport {

struct TcpOptions {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 0;  // 0: any free port
  uint32_t max_clients = 64;
  uint32_t max_message_bytes = 64u << 20;
  // Kernel send buffer per connection. Small, so that a slow newest-frame
  // reader gets recent frames instead of a backlog queued in the kernel.
  uint32_t send_buffer_bytes = 256u << 10;
};

// Binds and listens at once (so the port is known); serves after Start.
// Throws std::runtime_error naming the address if the port cannot be bound.
std::unique_ptr<Transport> MakeTcpTransport(const TcpOptions& options);

}  // namespace sim4cv::transport
