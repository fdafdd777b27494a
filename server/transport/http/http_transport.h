// The studio's HTTP port (docs/studio.md): the page's static files and, on
// the same port, a WebSocket transport of the protocol (docs/protocol.md,
// "WebSocket"): each WebSocket is one client session, exactly like a TCP
// connection, with Envelopes as JSON text messages and a Frame's pixels in a
// binary message after it, encoded (JPEG) on this transport's thread, never
// the sim thread. One Asio thread serves every connection.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "server/common/limits.h"
#include "server/transport/tcp/connection_deadlines.h"
#include "server/transport/transport.h"

namespace sim4cv::transport {

struct HttpOptions {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 0;  // 0: any free port
  // HTTP connections at once, WebSockets included; more are answered (503,
  // or TOO_MANY_CLIENTS) and closed.
  uint32_t max_clients = 32;
  // Connections the daemon's other transports may hold (TCP's
  // --max-clients), checked together against the descriptor limit.
  uint32_t other_connections = 0;
  std::string studio_dir;  // index.html and what it loads
  // A request (HTTP headers, a Hello, a started WebSocket message) must
  // arrive within these, as TCP's; idle_ms 0: WebSocket keep-alive pings only.
  TcpTimeouts timeouts = {limits::kDefaultHandshakeTimeoutMs, limits::kDefaultMessageTimeoutMs,
                          limits::kDefaultIdleTimeoutMs};
  // Kernel send buffer per connection: small, so a viewer that falls behind
  // gets the newest frame instead of a backlog queued in the kernel.
  uint32_t send_buffer_bytes = 256u << 10;
};

// Loads the studio's files and binds at once (so the port is known); serves
// after Start. Throws std::runtime_error naming the folder if it has no
// index.html, the address if the port cannot be bound, or the flags if the
// descriptor limit cannot hold every transport's connections.
std::unique_ptr<Transport> MakeHttpTransport(const HttpOptions& options);

}  // namespace sim4cv::transport
