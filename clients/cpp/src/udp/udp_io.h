// POSIX socket primitives behind sim4cv::UdpClient, apart from its session
// logic (as socket_io.h is for the TCP client).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>

namespace sim4cv::detail::udp {

using Deadline = std::chrono::steady_clock::time_point;

// A UDP socket connected to host:port (so it only hears from the daemon),
// with a large receive buffer (SO_RCVBUFFORCE when permitted, else
// SO_RCVBUF up to net.core.rmem_max). Sets `receive_buffer_bytes` to what the
// kernel granted. Throws ConnectionError naming the peer.
int Open(const std::string& host, uint16_t port, int& receive_buffer_bytes);

// Receives one datagram into data[0, capacity). Returns its size, or -1 if
// the deadline passed first. Throws ConnectionError naming `peer` on errors,
// e.g. when nothing listens on the port (ICMP port unreachable).
long Receive(int fd, uint8_t* data, std::size_t capacity, Deadline deadline, const std::string& peer);

// Sends one datagram. Throws ConnectionError naming `peer` on errors.
void Send(int fd, const void* data, std::size_t size, const std::string& peer);

}  // namespace sim4cv::detail::udp
