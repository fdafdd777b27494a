// One registered UDP client: its session::ClientSession (the same rules as
// TCP: protocol, frames and the sim thread's replies), the frame being cut
// into chunks, and the UDP-only state (sequence filter, last time heard
// from, Error rate limit, replies that met a full send buffer). Lives on the
// transport's thread; the sim thread only offers to the session, which
// wakes that thread through the Wakeup.
#pragma once

#include <atomic>
#include <chrono>
#include <deque>
#include <memory>
#include <vector>

#include "server/session/client_session.h"
#include "server/transport/frame_encoding.h"
#include "server/transport/udp/configure_history.h"
#include "server/transport/udp/frame_chunker.h"
#include "server/transport/udp/rate_limiter.h"
#include "server/transport/udp/sequence_filter.h"
#include "server/transport/udp/udp_socket.h"

namespace sim4cv::transport {

// Wakes the transport's thread from the sim thread: an eventfd written at
// most once per wake-up, however many frames arrive before the thread runs.
class Wakeup {
 public:
  Wakeup();
  ~Wakeup();
  Wakeup(const Wakeup&) = delete;
  Wakeup& operator=(const Wakeup&) = delete;

  void Notify();
  // The transport's thread, before it looks for work: later Notify calls
  // wake it again.
  void Clear();
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
  std::atomic<bool> pending_{false};
};

class UdpPeer {
 public:
  using Clock = std::chrono::steady_clock;

  UdpPeer(session::ClientId client, const PeerAddress& address, const session::ServerContext& context,
          std::shared_ptr<Wakeup> wakeup, std::size_t max_datagram_bytes, Clock::time_point now);

  // Creates the session; once, before anything else.
  void Start();

  // Transport thread: the sim thread's replies, oldest first, into `out` (cleared first).
  void TakeOfferedReplies(std::vector<proto::Envelope>& out) { session_->TakeReplies(out); }

  session::ClientId client() const { return client_; }
  const PeerAddress& address() const { return address_; }
  session::ClientProtocol& protocol() { return session_->protocol(); }
  SequenceFilter& sequence() { return sequence_; }
  RateLimiter& error_limit() { return error_limit_; }
  ConfigureHistory& configures() { return configures_; }

  // Replies that met a full send buffer, encoded, oldest first: they go
  // before anything else to this peer (a later frame must not overtake
  // them). Transport thread only.
  std::deque<std::string>& unsent_replies() { return unsent_replies_; }
  std::size_t& unsent_bytes() { return unsent_bytes_; }

  void Heard(Clock::time_point now) { last_heard_ = now; }
  Clock::time_point last_heard() const { return last_heard_; }

  // Frame sending. True if a frame is being chunked (after taking the next
  // one from the mailbox if none was); false if there is nothing to send, or
  // if a reply offered before the new frame must go first (the transport
  // sends it on its next turn, TakeOfferedReplies).
  bool NextFrame();
  const FrameChunker& chunker() const { return chunker_; }
  uint32_t next_chunk() const { return next_chunk_; }
  // `count` more chunks are with the kernel; ends the frame after its last.
  // True if that finished the frame.
  bool Advance(uint32_t count);
  // Gives up the rest of the current frame (a send failed).
  void AbandonFrame();

  // Forgets the client: tells the sim thread (if `disconnect`; a client
  // whose Hello was refused never reached it) and releases its frames.
  // Nothing may be called afterwards (the sim thread's offers are dropped).
  void Close(bool disconnect);

 private:
  void EndFrame();

  session::ClientId client_;
  PeerAddress address_;
  const session::ServerContext& context_;
  std::shared_ptr<Wakeup> wakeup_;
  std::shared_ptr<session::ClientSession> session_;

  SequenceFilter sequence_;
  RateLimiter error_limit_;
  ConfigureHistory configures_;
  Clock::time_point last_heard_;

  FrameEncoder encoder_;
  FrameChunker chunker_;
  session::FrameRef frame_in_flight_;
  uint32_t next_chunk_ = 0;
  std::deque<std::string> unsent_replies_;
  std::size_t unsent_bytes_ = 0;
};

}  // namespace sim4cv::transport
