// libsim4cv-client: a small blocking TCP client for sim4cvd. It depends only
// on the protocol (protocol/), never on server code.
//
//   sim4cv::Client client;
//   client.Connect("127.0.0.1", port);
//   client.Subscribe("uav", {CHANNEL_RGB, CHANNEL_BOXES}, sim4cv::proto::DELIVERY_LOCKSTEP);
//   for (...) { const auto& frame = client.StepAndReceive(); ... }
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "protocol/framing.h"
#include "sim4cv.pb.h"

namespace sim4cv {

// The daemon refused something: carries its code and message.
class ServerError : public std::runtime_error {
 public:
  ServerError(proto::ErrorCode code, const std::string& message, bool fatal);
  proto::ErrorCode code() const { return code_; }
  bool fatal() const { return fatal_; }

 private:
  proto::ErrorCode code_;
  bool fatal_;
};

// The connection failed, closed, timed out, or the peer broke the framing.
class ConnectionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A non-owning view of one channel's pixels inside a received Frame.
struct ImageView {
  const uint8_t* data = nullptr;
  uint32_t width = 0;
  uint32_t height = 0;
  uint32_t stride = 0;
  proto::PixelFormat format = proto::PIXEL_FORMAT_UNSPECIFIED;
};

// The channel's pixels in `frame`, or nullopt if the frame does not carry it.
std::optional<ImageView> FindImage(const proto::Frame& frame, proto::Channel channel);

class Client {
 public:
  using Duration = std::chrono::milliseconds;

  Client() = default;
  ~Client();
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;

  // Connects, sends Hello and waits for Welcome. Throws ServerError if the
  // daemon refuses (e.g. version mismatch), ConnectionError on I/O failure.
  void Connect(const std::string& host, uint16_t port, const std::string& client_name = "cpp-client",
               Duration timeout = Duration(5000), uint32_t protocol_version = 0 /* 0: this build's */);
  // Connects without the handshake (for tests that misbehave on purpose).
  void ConnectRaw(const std::string& host, uint16_t port, Duration timeout = Duration(5000));
  bool connected() const { return fd_ >= 0; }
  const proto::Welcome& welcome() const { return welcome_; }

  // Subscribes and waits for Subscribed. Throws ServerError on refusal,
  // ConnectionError on timeout. Frames of a previous subscription still
  // queued when Subscribed arrives are dropped.
  void Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels, proto::Delivery delivery,
                 bool with_state = false, Duration timeout = Duration(5000));

  // Lockstep: asks for the next frame.
  void Step();
  // Waits for the next Frame. Returns false on timeout. Throws ServerError if
  // an Error arrives first. The frame stays valid until the next receive.
  bool ReceiveFrame(proto::Frame& frame, Duration timeout = Duration(10000));
  // Step() then ReceiveFrame(); throws ConnectionError on timeout.
  const proto::Frame& StepAndReceive(Duration timeout = Duration(10000));

  void SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence);
  void SendControls(uint32_t entity_id, float steering, float throttle, float brake);
  // Sends GetState and waits for State. Frames arriving meanwhile are kept
  // for the next ReceiveFrame. A State already queued (the answer to a
  // GetState sent through SendEnvelope) is returned without a new request.
  // Throws ConnectionError on timeout.
  proto::State GetState(Duration timeout = Duration(5000));

  // Low level: one envelope out, with its length prefix.
  void SendEnvelope(const proto::Envelope& envelope);
  // Low level: raw bytes exactly as given (tests use it to send garbage).
  void SendRaw(const void* data, std::size_t size);
  // Low level: next envelope of any kind (queued ones first). False on timeout.
  // An Error is returned like any other envelope, not thrown.
  bool ReceiveEnvelope(proto::Envelope& envelope, Duration timeout);

  // Envelopes the server announces as larger than this are refused with a
  // ConnectionError (default: wire::kDefaultMaxMessageBytes, the daemon's).
  void set_max_message_bytes(uint32_t bytes) { max_message_bytes_ = bytes; }
  uint32_t max_message_bytes() const { return max_message_bytes_; }

  // Idempotent. Drops queued envelopes and any partly read one.
  void Close();

 private:
  using Deadline = std::chrono::steady_clock::time_point;

  // Reads until an envelope of `kind` arrives; others (except Error) queue.
  bool ReceiveKind(proto::Envelope::KindCase kind, proto::Envelope& out, Deadline deadline);
  // Reads the next envelope off the socket into scratch_. False on timeout; a
  // message cut by a timeout is resumed by the next call.
  bool ReadEnvelope(Deadline deadline);
  void ParseScratch(std::size_t size);
  [[noreturn]] void ThrowServerError(const proto::Error& error);  // closes first if fatal
  [[noreturn]] void FailConnection(const std::string& what);      // closes, names the peer
  void RequireConnected() const;

  int fd_ = -1;
  std::string peer_;  // "host:port", for error messages
  uint32_t max_message_bytes_ = wire::kDefaultMaxMessageBytes;
  proto::Welcome welcome_;
  proto::Envelope scratch_;
  proto::Frame frame_;
  std::deque<proto::Envelope> pending_;
  std::string buffer_;       // body of the envelope being read; only grows
  std::string send_buffer_;  // prefix + body of the envelope being sent

  // Progress of the envelope being read, kept across timeouts.
  uint8_t prefix_[wire::kLengthPrefixBytes] = {};
  std::size_t prefix_filled_ = 0;
  std::size_t body_size_ = 0;
  std::size_t body_filled_ = 0;
};

}  // namespace sim4cv
