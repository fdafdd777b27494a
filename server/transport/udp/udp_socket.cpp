#include "server/transport/udp/udp_socket.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "server/common/diagnostics.h"

namespace sim4cv::transport {
namespace {

// Kernel buffer sizes asked for; SO_*BUFFORCE (root) may exceed
// net.core.rmem_max / wmem_max, plain SO_*BUF is capped by them.
constexpr int kReceiveBufferBytes = 32 << 20;
constexpr int kSendBufferBytes = 8 << 20;

int SetBuffer(int fd, int force_option, int option, int bytes) {
  if (setsockopt(fd, SOL_SOCKET, force_option, &bytes, sizeof bytes) != 0) {
    setsockopt(fd, SOL_SOCKET, option, &bytes, sizeof bytes);
  }
  int actual = 0;
  socklen_t length = sizeof actual;
  getsockopt(fd, SOL_SOCKET, option, &actual, &length);
  return actual;
}

// The bytes that identify a peer: family, port and address.
std::size_t KeyBytes(const sockaddr_storage& storage, const uint8_t** out) {
  if (storage.ss_family == AF_INET) {
    const auto& in = reinterpret_cast<const sockaddr_in&>(storage);
    *out = reinterpret_cast<const uint8_t*>(&in.sin_addr);
    return sizeof in.sin_addr;
  }
  const auto& in6 = reinterpret_cast<const sockaddr_in6&>(storage);
  *out = reinterpret_cast<const uint8_t*>(&in6.sin6_addr);
  return sizeof in6.sin6_addr;
}

uint16_t PortOf(const sockaddr_storage& storage) {
  return storage.ss_family == AF_INET ? reinterpret_cast<const sockaddr_in&>(storage).sin_port
                                      : reinterpret_cast<const sockaddr_in6&>(storage).sin6_port;
}

}  // namespace

bool PeerAddress::operator==(const PeerAddress& other) const {
  if (storage.ss_family != other.storage.ss_family || PortOf(storage) != PortOf(other.storage)) return false;
  const uint8_t* a = nullptr;
  const uint8_t* b = nullptr;
  const std::size_t size = KeyBytes(storage, &a);
  KeyBytes(other.storage, &b);
  return std::memcmp(a, b, size) == 0;
}

std::size_t PeerAddress::Hash() const {
  const uint8_t* bytes = nullptr;
  const std::size_t size = KeyBytes(storage, &bytes);
  uint64_t hash = 1469598103934665603ull ^ PortOf(storage) ^ (static_cast<uint64_t>(storage.ss_family) << 16);
  for (std::size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 1099511628211ull;
  return static_cast<std::size_t>(hash);
}

std::string PeerAddress::ToString() const {
  char text[INET6_ADDRSTRLEN] = {};
  const uint8_t* bytes = nullptr;
  KeyBytes(storage, &bytes);
  inet_ntop(storage.ss_family, bytes, text, sizeof text);
  std::string out;
  if (storage.ss_family == AF_INET6) out.push_back('[');
  out.append(text);
  if (storage.ss_family == AF_INET6) out.push_back(']');
  out.push_back(':');
  out.append(std::to_string(ntohs(PortOf(storage))));
  return out;
}

UdpSocket::UdpSocket(const std::string& bind_address, uint16_t port) {
  sockaddr_storage storage{};
  socklen_t length = 0;
  auto& in = reinterpret_cast<sockaddr_in&>(storage);
  auto& in6 = reinterpret_cast<sockaddr_in6&>(storage);
  if (inet_pton(AF_INET, bind_address.c_str(), &in.sin_addr) == 1) {
    in.sin_family = AF_INET;
    in.sin_port = htons(port);
    length = sizeof in;
  } else if (inet_pton(AF_INET6, bind_address.c_str(), &in6.sin6_addr) == 1) {
    in6.sin6_family = AF_INET6;
    in6.sin6_port = htons(port);
    length = sizeof in6;
  } else {
    throw std::runtime_error("--bind '" + bind_address + "' is not an IP address");
  }
  fd_ = socket(storage.ss_family, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error(std::string("cannot create a UDP socket: ") + std::strerror(errno));
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&storage), length) != 0) {
    const int error = errno;
    close(fd_);
    throw std::runtime_error("cannot bind UDP " + bind_address + ":" + std::to_string(port) + ": " +
                             std::strerror(error) + " (pick another --udp-port, 0 for any free port, -1 for no UDP)");
  }
  socklen_t bound_length = sizeof storage;
  getsockname(fd_, reinterpret_cast<sockaddr*>(&storage), &bound_length);
  port_ = ntohs(PortOf(storage));
  receive_buffer_bytes_ = SetBuffer(fd_, SO_RCVBUFFORCE, SO_RCVBUF, kReceiveBufferBytes);
  SetBuffer(fd_, SO_SNDBUFFORCE, SO_SNDBUF, kSendBufferBytes);
  const int on = 1;
  setsockopt(fd_, SOL_SOCKET, SO_RXQ_OVFL, &on, sizeof on);  // count what the kernel drops
}

UdpSocket::~UdpSocket() {
  if (fd_ >= 0) close(fd_);
}

DatagramBatch::DatagramBatch() : buffers_(kDatagrams * kBufferBytes) {}

std::size_t DatagramBatch::Receive(int fd) {
  for (std::size_t i = 0; i < kDatagrams; ++i) {
    iovecs_[i] = {buffers_.data() + i * kBufferBytes, kBufferBytes};
    msghdr& header = headers_[i].msg_hdr;
    header = {};
    header.msg_name = &addresses_[i].storage;
    header.msg_namelen = sizeof addresses_[i].storage;
    header.msg_iov = &iovecs_[i];
    header.msg_iovlen = 1;
    header.msg_control = controls_[i].data();
    header.msg_controllen = controls_[i].size();
    headers_[i].msg_len = 0;
  }
  int got = -1;
  do {
    got = recvmmsg(fd, headers_.data(), kDatagrams, MSG_DONTWAIT, nullptr);
  } while (got < 0 && errno == EINTR);
  if (got < 0) {
    if (errno != EAGAIN && errno != EWOULDBLOCK) LOG_INFO("UDP receive failed: " << std::strerror(errno));
    return 0;
  }
  for (int i = 0; i < got; ++i) {
    msghdr& header = headers_[i].msg_hdr;
    addresses_[i].length = header.msg_namelen;
    for (cmsghdr* c = CMSG_FIRSTHDR(&header); c != nullptr; c = CMSG_NXTHDR(&header, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) std::memcpy(&kernel_drops_, CMSG_DATA(c), sizeof kernel_drops_);
    }
  }
  return static_cast<std::size_t>(got);
}

}  // namespace sim4cv::transport
