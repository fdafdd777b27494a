// A TCP connection to the daemon that behaves as a hostile client may: it
// sends exactly the bytes given, as fast as the socket takes them or one at a
// time, and reads only when asked. For tests of what a client can make the
// daemon hold or wait for; well-behaved clients use sim4cv::Client.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include "protocol/framing.h"
#include "sim4cv.pb.h"

namespace sim4cv::testing {

// Prefix + serialized envelope, as on the wire.
inline std::string Framed(const proto::Envelope& envelope) {
  std::string bytes(wire::kLengthPrefixBytes, '\0');
  envelope.AppendToString(&bytes);
  wire::EncodeLengthPrefix(static_cast<uint32_t>(bytes.size() - wire::kLengthPrefixBytes),
                           reinterpret_cast<uint8_t*>(bytes.data()));
  return bytes;
}

// `token`: the daemon's access token (DaemonProcess::access_token).
inline std::string FramedHello(const std::string& name, const std::string& token) {
  proto::Envelope hello;
  hello.mutable_hello()->set_protocol_version(wire::kProtocolVersion);
  hello.mutable_hello()->set_client_name(name);
  hello.mutable_hello()->set_token(token);
  return Framed(hello);
}

// CPU seconds (user + system) the process `pid` has used, from /proc/PID/stat.
inline double CpuSeconds(int pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string text((std::istreambuf_iterator<char>(stat)), std::istreambuf_iterator<char>());
  std::istringstream fields(text.substr(text.rfind(')') + 2));  // after "pid (comm) "
  std::string field;
  double ticks = 0;
  for (int i = 3; i <= 15 && fields >> field; ++i) {
    if (i == 14 || i == 15) ticks += std::stod(field);  // utime, stime
  }
  return ticks / static_cast<double>(sysconf(_SC_CLK_TCK));
}

class RawConnection {
 public:
  using Clock = std::chrono::steady_clock;

  explicit RawConnection(uint16_t port) : fd_(socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) {
    if (fd_ < 0) throw std::runtime_error("socket failed");
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
      close(fd_);
      throw std::runtime_error("connect failed");
    }
    const int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fcntl(fd_, F_SETFL, fcntl(fd_, F_GETFL) | O_NONBLOCK);
  }
  ~RawConnection() { Close(); }
  RawConnection(const RawConnection&) = delete;
  RawConnection& operator=(const RawConnection&) = delete;

  void Close() {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
  }

  // Sends what the socket takes now, without waiting; returns the count (0
  // when full; -1 once the daemon closed the connection).
  long TrySend(const char* data, std::size_t size) {
    const ssize_t sent = send(fd_, data, size, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (sent >= 0) return sent;
    return errno == EAGAIN || errno == EWOULDBLOCK ? 0 : -1;
  }

  // Sends all of `bytes`, waiting up to `timeout` for room. False if it could not.
  bool Send(const std::string& bytes, std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
    const auto deadline = Clock::now() + timeout;
    std::size_t done = 0;
    while (done < bytes.size()) {
      const long sent = TrySend(bytes.data() + done, bytes.size() - done);
      if (sent < 0 || Clock::now() > deadline) return false;
      done += static_cast<std::size_t>(sent);
      if (sent == 0) Wait(POLLOUT, deadline);
    }
    return true;
  }

  // The next envelope the daemon sent, if one came within `timeout`; sets
  // closed() when the daemon closed the connection instead.
  std::optional<proto::Envelope> Receive(std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
    const auto deadline = Clock::now() + timeout;
    while (true) {
      if (in_.size() >= wire::kLengthPrefixBytes) {
        const uint32_t size = wire::DecodeLengthPrefix(reinterpret_cast<const uint8_t*>(in_.data()));
        if (in_.size() >= wire::kLengthPrefixBytes + size) {
          proto::Envelope envelope;
          envelope.ParseFromArray(in_.data() + wire::kLengthPrefixBytes, static_cast<int>(size));
          in_.erase(0, wire::kLengthPrefixBytes + size);
          return envelope;
        }
      }
      if (closed_ || Clock::now() > deadline) return std::nullopt;
      char buffer[65536];
      const ssize_t got = recv(fd_, buffer, sizeof buffer, MSG_DONTWAIT);
      if (got > 0) {
        in_.append(buffer, static_cast<std::size_t>(got));
      } else if (got == 0 || (errno != EAGAIN && errno != EWOULDBLOCK)) {
        closed_ = true;
      } else {
        Wait(POLLIN, deadline);
      }
    }
  }

  // Reads and discards until the daemon closes the connection or `timeout`
  // passes; returns the first Error it sent, if any.
  std::optional<proto::Error> ErrorThenClose(std::chrono::milliseconds timeout = std::chrono::milliseconds(10000)) {
    const auto deadline = Clock::now() + timeout;
    std::optional<proto::Error> error;
    while (!closed_ && Clock::now() < deadline) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      const auto envelope = Receive(left);
      if (envelope && envelope->has_error() && !error) error = envelope->error();
    }
    return error;
  }

  bool closed() const { return closed_; }

 private:
  void Wait(short events, Clock::time_point deadline) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
    pollfd pfd{fd_, events, 0};
    poll(&pfd, 1, static_cast<int>(std::clamp<long>(left, 0, 100)));
  }

  int fd_;
  std::string in_;
  bool closed_ = false;
};

}  // namespace sim4cv::testing
