// One attached shared-memory client's area, daemon side: a memfd of
// shm::kAreaBytes that this client alone maps read-write besides the daemon
// (its request ring to the daemon, its response ring back), sealed against
// shrinking and growing so that nothing the client does to it can make a
// daemon access fault. The daemon trusts nothing it reads from it: its
// indices are its own, the client's request count and sizes are checked
// against the ring before use, and every request is copied out before it is
// parsed. What a client writes there reaches no other client. A response too
// long for a response message goes on the client's attachment socket, and the
// ring says so (docs/protocol.md 13.5).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "protocol/shm_sync.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

class ShmClientArea {
 public:
  // Creates, maps, fills and seals the area for the client attached through
  // `socket`, which stays the caller's to close, after MarkClosed (nothing is
  // sent on it after that). Throws std::runtime_error.
  explicit ShmClientArea(int socket);
  ~ShmClientArea();
  ShmClientArea(const ShmClientArea&) = delete;
  ShmClientArea& operator=(const ShmClientArea&) = delete;

  // The memfd, to send to the client; CloseFd once sent (the mapping stays).
  int fd() const { return fd_; }
  void CloseFd();

  // Shm thread: the client's next request.
  enum class Take {
    kMessage,  // `data`/`size` hold a copy of it, valid until the next call
    kEmpty,    // the client wrote nothing more
    kBroken,   // the client broke the ring's rules; `why` says how (end its attachment)
  };
  Take Next(const uint8_t*& data, uint32_t& size, std::string& why);

  // Writes `reply` as the next response and wakes the client: into the ring,
  // or, past kShmResponseDataBytes, onto the socket with the ring saying so.
  // One caller at a time (the client's ShmClientLink sees to that).
  enum class Written {
    kDone,
    kTooLarge,    // over kShmSocketResponseBytes: nothing written
    kSocketFull,  // the client left earlier long responses unread: nothing written
  };
  Written Write(const proto::Envelope& reply);
  // Tells the client its attachment is over (closed = 1) and wakes it. Same
  // caller rule as Write; nothing is written after it.
  void MarkClosed();

  const shm::AreaMap& map() const { return map_; }

 private:
  // Publishes response written_ in the ring (its Envelope in `data` unless
  // `on_socket`) and wakes the client.
  void Publish(const proto::Envelope& reply, uint32_t size, bool on_socket);

  shm::AreaMap map_;
  int fd_ = -1;
  int socket_ = -1;  // not owned
  uint64_t read_ = 0;     // next request to take (the daemon's own count)
  uint64_t written_ = 0;  // responses written (own count)
  uint32_t futex_ = 0;    // last value stored into response_futex (own count)
  std::array<uint8_t, shm::kShmRequestDataBytes> buffer_{};
  std::string long_response_;  // a long response's socket message, kept for the next
};

}  // namespace sim4cv::transport
