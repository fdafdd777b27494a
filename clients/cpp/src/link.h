// One adapter per transport behind sim4cv::Client (after LibCarla's
// streaming/ facade over detail/tcp/): a Link moves envelopes to and from
// the daemon; the Client decides what they mean (matching answers to
// requests, retries, queues). A new transport is one new Link and one line
// in OpenLink (address.cpp).
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "sim4cv.pb.h"

namespace sim4cv {
class UdpClient;
class ShmClient;
}  // namespace sim4cv

namespace sim4cv::detail {

using Deadline = std::chrono::steady_clock::time_point;

// The time left until `deadline` (zero once past), for the transports'
// own clients, which take timeouts.
inline std::chrono::milliseconds Until(Deadline deadline) {
  return std::max(std::chrono::milliseconds(0),
                  std::chrono::ceil<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now()));
}

class Link {
 public:
  virtual ~Link() = default;

  // The address it was opened with ("tcp://127.0.0.1:5000"), for messages.
  virtual const std::string& address() const = 0;
  // Hello, answered by Welcome (retried on lossy links). Throws ServerError
  // if the daemon refuses, ConnectionError at the deadline.
  virtual proto::Welcome Hello(const std::string& client_name, uint32_t protocol_version, Deadline deadline) = 0;
  virtual void Send(const proto::Envelope& envelope) = 0;
  // Bytes as they are (tests send garbage with it).
  virtual void SendRaw(const void* data, std::size_t size) = 0;
  // The next envelope from the daemon (a frame arrives whole), false at the
  // deadline. `frame_wanted`: the caller waits for a frame; a link whose
  // frames do not come in its message stream (shared memory) yields the
  // newest frame it was not asked for yet only then.
  virtual bool Receive(proto::Envelope& out, Deadline deadline, bool frame_wanted) = 0;
  // How often a request whose answer has not come is sent again; zero: the
  // link loses nothing, never.
  virtual std::chrono::milliseconds retry_interval() const { return {}; }
  // Where Configure goes: this link, unless its messages are too small for
  // Configure's (shared memory opens a TCP link to the same daemon).
  virtual Link& configure_link() { return *this; }
  virtual void set_max_message_bytes(uint32_t /*bytes*/) {}
  virtual bool open() const = 0;
  virtual void Close() = 0;

  // The transport's own client, for its optional knobs; nullptr if another.
  virtual UdpClient* udp() { return nullptr; }
  virtual ShmClient* shm() { return nullptr; }
};

std::unique_ptr<Link> OpenTcpLink(const std::string& host, uint16_t port, Deadline deadline,
                                  uint32_t max_message_bytes);
std::unique_ptr<Link> OpenUdpLink(const std::string& host, uint16_t port);
std::unique_ptr<Link> OpenShmLink(const std::string& name);

}  // namespace sim4cv::detail

namespace sim4cv::detail {
// The link `address` names (tcp://HOST:PORT, udp://HOST:PORT, shm://NAME);
// std::invalid_argument naming the address if it is none of those.
std::unique_ptr<Link> OpenLink(const std::string& address, Deadline deadline, uint32_t max_message_bytes);
}  // namespace sim4cv::detail
