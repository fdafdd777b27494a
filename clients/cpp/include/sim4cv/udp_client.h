// sim4cv::UdpClient: the UDP transport of libsim4cv-client (docs/protocol.md
// section 12). One Envelope per datagram; frames arrive as FrameChunks and
// are reassembled here; requests that expect a reply are retried until it
// comes. Depends only on the protocol (protocol/).
//
//   sim4cv::UdpClient client;
//   client.Connect("127.0.0.1", udp_port);
//   client.Subscribe("uav", {CHANNEL_RGB, CHANNEL_BOXES}, sim4cv::proto::DELIVERY_LOCKSTEP);
//   proto::Frame frame;
//   for (...) { client.Step(); if (client.ReceiveFrame(frame)) ...; }
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "sim4cv/client.h"  // ServerError, ConnectionError, ImageView, FindImage
#include "sim4cv.pb.h"

namespace sim4cv {

namespace detail {
class FrameReassembler;
}

class UdpClient {
 public:
  using Duration = std::chrono::milliseconds;

  UdpClient();
  ~UdpClient();
  UdpClient(const UdpClient&) = delete;
  UdpClient& operator=(const UdpClient&) = delete;

  // Opens the socket, sends Hello (again every `retry_interval()` until an
  // answer comes) and waits for Welcome. Throws ServerError if the daemon
  // refuses (e.g. VERSION_MISMATCH), ConnectionError if nothing answers
  // within `timeout` or nothing listens on the port. A Welcome arriving after
  // Connect returned (the answer to a repeated Hello) is dropped.
  void Connect(const std::string& host, uint16_t port, const std::string& client_name = "cpp-udp-client",
               Duration timeout = Duration(5000), uint32_t protocol_version = 0 /* 0: this build's */);
  // Opens the socket without the handshake (for tests that misbehave on purpose).
  void Open(const std::string& host, uint16_t port);
  bool connected() const { return fd_ >= 0; }
  const proto::Welcome& welcome() const { return welcome_; }

  // Subscribes (retrying until Subscribed) and waits for Subscribed. Throws
  // ServerError on refusal, ConnectionError on timeout. Frames of a previous
  // subscription completed before Subscribed are dropped.
  void Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels, proto::Delivery delivery,
                 bool with_state = false, Duration timeout = Duration(5000));

  // Lockstep: asks for the next frame. Not retried: if the frame is lost on
  // the way, ReceiveFrame times out and the caller Steps again.
  void Step();
  // Waits for the next complete Frame. Returns false on timeout. Throws
  // ServerError if an Error arrives first. While waiting it sends a
  // keep-alive whenever nothing was sent for `keepalive_interval()`.
  bool ReceiveFrame(proto::Frame& frame, Duration timeout = Duration(10000));
  // On-request delivery (DELIVERY_ON_REQUEST): asks for a frame (NextFrame,
  // repeated every retry interval: a lost request or chunk costs one
  // interval) and waits for it: the newest this client was not sent yet,
  // else the next one rendered. Frames queued before are dropped as stale.
  // Returns false on timeout; throws ServerError if the daemon refuses.
  bool RequestFrame(proto::Frame& frame, Duration timeout = Duration(10000));

  void SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence);
  void SendControls(uint32_t entity_id, float steering, float throttle, float brake);
  // Sends GetState (retrying) and waits for State. State replies queued
  // earlier are stale over UDP and discarded first. Throws ConnectionError
  // on timeout.
  proto::State GetState(Duration timeout = Duration(5000));
  // The same for GetStats: the daemon's counters.
  proto::Stats GetStats(Duration timeout = Duration(5000));
  // An Envelope with no message: keeps the registration alive, no reply.
  void SendKeepAlive();

  // Low level: one envelope, given the next sequence number. Returns it.
  uint64_t SendEnvelope(const proto::Envelope& envelope);
  // Low level: one envelope with exactly this sequence (0: none), e.g. to
  // send a duplicate on purpose.
  void SendEnvelope(const proto::Envelope& envelope, uint64_t sequence);
  // Low level: one datagram with exactly these bytes.
  void SendRaw(const void* data, std::size_t size);
  // Low level: the next envelope of any kind (queued ones first); a frame
  // comes complete as Envelope.frame. An Error is returned, not thrown.
  // False on timeout.
  bool ReceiveEnvelope(proto::Envelope& envelope, Duration timeout);

  // The sequence the next SendEnvelope will use.
  uint64_t next_sequence() const { return next_sequence_; }
  // How often requests are re-sent while their reply is awaited (250 ms).
  Duration retry_interval() const { return retry_interval_; }
  // Longest silence towards the daemon while waiting (default 1000 ms; the
  // daemon forgets clients after --udp-expiry-ms, 5000 by default).
  void set_keepalive_interval(Duration interval) { keepalive_interval_ = interval; }
  Duration keepalive_interval() const { return keepalive_interval_; }
  // Kernel receive buffer actually granted (frames arrive in bursts).
  int receive_buffer_bytes() const { return receive_buffer_bytes_; }

  // Reassembly counters since Connect/Open.
  uint64_t frames_completed() const;
  uint64_t frames_dropped_incomplete() const;  // a chunk never came; a newer frame overtook it
  uint64_t chunks_ignored() const;             // bad index or sizes, duplicates, finished or unknown frames
  uint64_t datagrams_malformed() const { return datagrams_malformed_; }  // not an Envelope, or a frame that does not parse

  // Idempotent. The daemon forgets the client after --udp-expiry-ms.
  void Close();

 private:
  using Deadline = std::chrono::steady_clock::time_point;

  // Sends `request` now and again every retry interval until an envelope of
  // `kind` arrives (returned in `out`) or the deadline passes (false).
  bool Request(const proto::Envelope& request, proto::Envelope::KindCase kind, proto::Envelope& out, Deadline deadline);
  // Reads until an envelope of `kind` arrives; others (except Error, which
  // is thrown) queue. False at `deadline`.
  bool ReceiveKind(proto::Envelope::KindCase kind, proto::Envelope& out, Deadline deadline);
  // Reads datagrams until one yields an envelope in scratch_ (a complete
  // frame or a message). False at the deadline.
  bool ReadEnvelope(Deadline deadline);
  bool ParseFrame();
  [[noreturn]] void ThrowServerError(const proto::Error& error);
  void RequireConnected() const;

  int fd_ = -1;
  std::string peer_;  // "host:port", for error messages
  int receive_buffer_bytes_ = 0;
  proto::Welcome welcome_;
  uint64_t next_sequence_ = 1;
  Duration retry_interval_{250};
  Duration keepalive_interval_{1000};
  std::chrono::steady_clock::time_point last_send_{};
  std::unique_ptr<detail::FrameReassembler> reassembler_;
  uint64_t datagrams_malformed_ = 0;
  proto::Envelope scratch_;
  std::deque<proto::Envelope> pending_;
  std::vector<uint8_t> datagram_;  // receive buffer, one datagram
  std::string send_buffer_;
};

}  // namespace sim4cv
