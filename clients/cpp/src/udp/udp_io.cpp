#include "udp_io.h"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "sim4cv/client.h"

namespace sim4cv::detail::udp {
namespace {

constexpr int kReceiveBufferBytes = 32 << 20;

[[noreturn]] void Fail(const std::string& what, const std::string& peer, int error) {
  if (error == ECONNREFUSED) {
    throw ConnectionError("nothing listens on UDP " + peer + " (the host answered 'port unreachable'); check the "
                          "daemon's udp= port on its listening line");
  }
  throw ConnectionError(what + " " + peer + ": " + std::strerror(error));
}

int PollTimeoutMs(Deadline deadline) {
  const auto left = deadline - std::chrono::steady_clock::now();
  if (left <= Deadline::duration::zero()) return 0;
  return static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(left).count());
}

}  // namespace

int Open(const std::string& host, uint16_t port, int& receive_buffer_bytes) {
  const std::string peer = host + ":" + std::to_string(port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* addresses = nullptr;
  const int resolved = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &addresses);
  if (resolved != 0) throw ConnectionError("cannot resolve " + peer + ": " + gai_strerror(resolved));
  int fd = -1;
  int error = 0;
  for (const addrinfo* a = addresses; a != nullptr && fd < 0; a = a->ai_next) {
    fd = socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      error = errno;
    } else if (connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      error = errno;
      close(fd);
      fd = -1;
    }
  }
  freeaddrinfo(addresses);
  if (fd < 0) Fail("cannot open a UDP socket to", peer, error);
  // Frames arrive as bursts of datagrams; what does not fit is dropped by the kernel.
  int bytes = kReceiveBufferBytes;
  if (setsockopt(fd, SOL_SOCKET, SO_RCVBUFFORCE, &bytes, sizeof bytes) != 0) {
    setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
  }
  socklen_t length = sizeof receive_buffer_bytes;
  getsockopt(fd, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, &length);
  return fd;
}

long Receive(int fd, uint8_t* data, std::size_t capacity, Deadline deadline, const std::string& peer) {
  while (true) {
    const ssize_t got = recv(fd, data, capacity, MSG_DONTWAIT);
    if (got >= 0) return static_cast<long>(got);
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != EWOULDBLOCK) Fail("cannot receive from", peer, errno);
    pollfd entry{fd, POLLIN, 0};
    const int ready = poll(&entry, 1, PollTimeoutMs(deadline));
    if (ready == 0) return -1;
    if (ready < 0 && errno != EINTR) Fail("poll failed on the socket to", peer, errno);
  }
}

void Send(int fd, const void* data, std::size_t size, const std::string& peer) {
  while (send(fd, data, size, MSG_NOSIGNAL) < 0) {
    if (errno != EINTR) Fail("cannot send to", peer, errno);
  }
}

}  // namespace sim4cv::detail::udp
