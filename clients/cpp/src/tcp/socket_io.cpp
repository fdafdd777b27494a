#include "socket_io.h"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "sim4cv/client.h"

namespace sim4cv::detail {
namespace {

std::string Endpoint(const std::string& host, uint16_t port) { return host + ":" + std::to_string(port); }

[[noreturn]] void ThrowErrno(const std::string& what, const std::string& peer, int error) {
  throw ConnectionError(what + " " + peer + ": " + std::strerror(error));
}

// poll()'s timeout for `deadline`, rounded up so that poll never returns
// before the deadline has really passed.
int PollTimeoutMs(Deadline deadline) {
  const auto left = deadline - std::chrono::steady_clock::now();
  if (left <= Deadline::duration::zero()) return 0;
  return static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(left).count());
}

// True once `events` are ready on fd (or it has an error or hang-up, which the
// following syscall reports); false when the deadline passes first.
bool WaitFor(int fd, short events, Deadline deadline, const std::string& peer) {
  while (true) {
    pollfd entry{fd, events, 0};
    const int ready = poll(&entry, 1, PollTimeoutMs(deadline));
    if (ready > 0) return true;
    if (ready == 0) return false;
    if (errno != EINTR) ThrowErrno("poll failed on the connection to", peer, errno);
  }
}

// connect() within the deadline; returns 0 or the errno of the failure.
int ConnectWithin(int fd, const addrinfo& address, Deadline deadline, const std::string& peer) {
  if (connect(fd, address.ai_addr, address.ai_addrlen) == 0) return 0;
  if (errno != EINPROGRESS && errno != EINTR) return errno;
  if (!WaitFor(fd, POLLOUT, deadline, peer)) return ETIMEDOUT;
  int error = 0;
  socklen_t length = sizeof error;
  if (getsockopt(fd, SOL_SOCKET, SO_ERROR, &error, &length) != 0) return errno;
  return error;
}

// Returns 0 or the errno of the failing call.
int MakeBlockingWithoutNagle(int fd) {
  const int flags = fcntl(fd, F_GETFL);
  if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) return errno;
  const int no_delay = 1;
  if (setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &no_delay, sizeof no_delay) != 0) return errno;
  return 0;
}

// One attempt on one resolved address; returns the socket, or -1 with `error` set.
int TryConnect(const addrinfo& address, Deadline deadline, const std::string& peer, int& error) {
  // Non-blocking only while connecting, so that connecting honours the deadline.
  const int fd = socket(address.ai_family, address.ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, address.ai_protocol);
  if (fd < 0) {
    error = errno;
    return -1;
  }
  error = ConnectWithin(fd, address, deadline, peer);
  if (error == 0) error = MakeBlockingWithoutNagle(fd);
  if (error == 0) return fd;
  close(fd);
  return -1;
}

}  // namespace

int ConnectTcp(const std::string& host, uint16_t port, Deadline deadline) {
  const std::string peer = Endpoint(host, port);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* addresses = nullptr;
  const int resolved = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &addresses);
  if (resolved != 0) throw ConnectionError("cannot resolve " + peer + ": " + gai_strerror(resolved));
  int error = 0;
  int fd = -1;
  for (const addrinfo* address = addresses; address != nullptr && fd < 0; address = address->ai_next) {
    fd = TryConnect(*address, deadline, peer, error);
  }
  freeaddrinfo(addresses);
  if (fd < 0) ThrowErrno("cannot connect to", peer, error);
  return fd;
}

ReadStatus ReadUntil(int fd, uint8_t* data, std::size_t size, std::size_t& filled, Deadline deadline,
                     const std::string& peer) {
  while (filled < size) {
    // Try the read first: when the data is already there (the common case
    // for a frame's body) this saves the poll() syscall.
    const ssize_t got = recv(fd, data + filled, size - filled, MSG_DONTWAIT);
    if (got > 0) {
      filled += static_cast<std::size_t>(got);
    } else if (got == 0) {
      throw ConnectionError("sim4cvd at " + peer + " closed the connection");
    } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
      if (!WaitFor(fd, POLLIN, deadline, peer)) return ReadStatus::kTimeout;
    } else if (errno != EINTR) {
      ThrowErrno("cannot read from", peer, errno);
    }
  }
  return ReadStatus::kComplete;
}

void WriteAll(int fd, const void* data, std::size_t size, const std::string& peer) {
  const auto* bytes = static_cast<const uint8_t*>(data);
  std::size_t sent = 0;
  while (sent < size) {
    const ssize_t wrote = send(fd, bytes + sent, size - sent, MSG_NOSIGNAL);
    if (wrote >= 0) {
      sent += static_cast<std::size_t>(wrote);
    } else if (errno != EINTR) {
      ThrowErrno("cannot write to", peer, errno);
    }
  }
}

}  // namespace sim4cv::detail
