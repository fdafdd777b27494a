// UDP adapter: one Envelope per datagram; frames cut into FrameChunks that
// fit --udp-datagram-bytes; clients register with Hello and expire after
// --udp-expiry-ms of silence.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "server/transport/transport.h"

namespace sim4cv::transport {

struct UdpOptions {
  std::string bind_address = "127.0.0.1";
  uint16_t port = 0;                    // 0: any free port
  uint32_t max_datagram_bytes = 65000;  // loopback default; 1472 suits a 1500-byte MTU
  uint32_t expiry_ms = 5000;            // a registration lapses after this much silence
  uint32_t max_clients = 64;
};

// Binds at once (so the port is known); serves after Start. Throws
// std::runtime_error naming the address if the port cannot be bound.
std::unique_ptr<Transport> MakeUdpTransport(const UdpOptions& options);

}  // namespace sim4cv::transport
