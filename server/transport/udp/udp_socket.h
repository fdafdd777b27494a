// POSIX pieces of the UDP transport: the bound non-blocking socket (large
// kernel buffers, kernel drop counting) and batched receiving with recvmmsg.
#pragma once

#include <netinet/in.h>
#include <sys/socket.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sim4cv::transport {

// A peer's address, usable as a hash-map key.
struct PeerAddress {
  sockaddr_storage storage{};
  socklen_t length = 0;

  bool operator==(const PeerAddress& other) const;
  std::size_t Hash() const;
  std::string ToString() const;  // "1.2.3.4:5678" or "[::1]:5678"
};

struct PeerAddressHash {
  std::size_t operator()(const PeerAddress& address) const { return address.Hash(); }
};

class UdpSocket {
 public:
  // Binds a non-blocking socket. Throws std::runtime_error naming the
  // address and port if it cannot.
  UdpSocket(const std::string& bind_address, uint16_t port);
  ~UdpSocket();
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  int fd() const { return fd_; }
  uint16_t port() const { return port_; }
  int receive_buffer_bytes() const { return receive_buffer_bytes_; }

 private:
  int fd_ = -1;
  uint16_t port_ = 0;
  int receive_buffer_bytes_ = 0;
};

// Reused buffers for reading many datagrams per system call.
class DatagramBatch {
 public:
  static constexpr std::size_t kDatagrams = 32;
  // Larger than any UDP/IPv4 payload, so only IPv6 jumbograms can be truncated.
  static constexpr std::size_t kBufferBytes = 65536;

  DatagramBatch();

  // Reads up to kDatagrams waiting datagrams without blocking. Returns how
  // many (0 when none is waiting).
  std::size_t Receive(int fd);

  const uint8_t* data(std::size_t i) const { return buffers_.data() + i * kBufferBytes; }
  std::size_t size(std::size_t i) const { return headers_[i].msg_len; }
  bool truncated(std::size_t i) const { return (headers_[i].msg_hdr.msg_flags & MSG_TRUNC) != 0; }
  const PeerAddress& address(std::size_t i) const { return addresses_[i]; }
  // Datagrams the kernel has dropped on this socket so far because its
  // receive buffer was full (SO_RXQ_OVFL), as of the last Receive.
  uint32_t kernel_drops() const { return kernel_drops_; }

 private:
  std::vector<uint8_t> buffers_;
  std::array<mmsghdr, kDatagrams> headers_{};
  std::array<iovec, kDatagrams> iovecs_{};
  std::array<PeerAddress, kDatagrams> addresses_{};
  std::array<std::array<uint8_t, 64>, kDatagrams> controls_{};
  uint32_t kernel_drops_ = 0;
};

}  // namespace sim4cv::transport
