// The TCP link: envelopes with a 4-byte length prefix over one stream
// socket (docs/protocol.md section 2). A message cut by a timeout is
// resumed by the next Receive; frames parse into reused buffers.
#include <google/protobuf/io/coded_stream.h>
#include <unistd.h>

#include <algorithm>
#include <climits>

#include "../link.h"
#include "../requests.h"
#include "protocol/framing.h"
#include "sim4cv/client.h"
#include "socket_io.h"

namespace sim4cv::detail {
namespace {

using Envelope = proto::Envelope;

// First byte of an Envelope that carries a Frame (field number, wire type 2).
constexpr std::size_t kFirstPieceBytes = std::size_t{1} << 20;  // buffer for a message's first bytes
constexpr uint8_t kFrameFieldTag = (Envelope::kFrameFieldNumber << 3) | 2;

class TcpLink : public Link {
 public:
  TcpLink(const std::string& host, uint16_t port, Deadline deadline, uint32_t max_message_bytes)
      : address_("tcp://" + host + ":" + std::to_string(port)),
        token_(AccessToken("tcp", host, port)),
        max_message_bytes_(max_message_bytes),
        fd_(ConnectTcp(host, port, deadline)) {}
  ~TcpLink() override { Close(); }

  const std::string& address() const override { return address_; }

  proto::Welcome Hello(const std::string& client_name, uint32_t protocol_version, Deadline deadline) override {
    Send(HelloRequest(client_name, protocol_version, token_));
    Envelope reply;
    // Nothing but the answer comes before Welcome.
    if (!Receive(reply, deadline, false)) throw ConnectionError("timed out waiting for Welcome from " + address_);
    if (reply.has_error()) {
      Close();
      throw ServerError(reply.error().code(), reply.error().message(), reply.error().fatal());
    }
    if (!reply.has_welcome()) Fail("sim4cvd answered Hello with something else than Welcome");
    return std::move(*reply.mutable_welcome());
  }

  void Send(const Envelope& envelope) override {
    const std::size_t body_size = envelope.ByteSizeLong();
    if (body_size > UINT32_MAX) throw std::length_error("envelope of " + std::to_string(body_size) + " bytes");
    // Prefix and body in one buffer so that each envelope is one send().
    send_buffer_.resize(wire::kLengthPrefixBytes + body_size);
    auto* bytes = reinterpret_cast<uint8_t*>(send_buffer_.data());
    wire::EncodeLengthPrefix(static_cast<uint32_t>(body_size), bytes);
    envelope.SerializeWithCachedSizesToArray(bytes + wire::kLengthPrefixBytes);
    SendRaw(bytes, send_buffer_.size());
  }

  void SendRaw(const void* data, std::size_t size) override {
    RequireOpen();
    try {
      WriteAll(fd_, data, size, address_);
    } catch (const ConnectionError&) {
      Close();
      throw;
    }
  }

  bool Receive(Envelope& out, Deadline deadline, bool /*frame_wanted*/) override {
    RequireOpen();
    try {
      if (prefix_filled_ < wire::kLengthPrefixBytes) {
        if (ReadUntil(fd_, prefix_, sizeof prefix_, prefix_filled_, deadline, address_) == ReadStatus::kTimeout) {
          return false;
        }
        body_size_ = wire::DecodeLengthPrefix(prefix_);
        // CodedInputStream takes an int size, so INT_MAX caps any limit.
        if (body_size_ > std::min<std::size_t>(max_message_bytes_, INT_MAX)) {
          Fail("sim4cvd announced a message of " + std::to_string(body_size_) + " bytes, more than the limit of " +
               std::to_string(max_message_bytes_));
        }
        body_filled_ = 0;
      }
      // The buffer grows with what arrives, doubling (never shrinks: resizing
      // down and up again would zero-fill each time), so a peer that
      // announces 64 MiB and sends a few bytes costs 1 MiB, not 64.
      while (body_filled_ < body_size_) {
        const std::size_t piece_end =
            std::min(body_size_, std::max({buffer_.size(), kFirstPieceBytes, 2 * body_filled_}));
        if (buffer_.size() < piece_end) buffer_.resize(piece_end);
        if (ReadUntil(fd_, reinterpret_cast<uint8_t*>(buffer_.data()), piece_end, body_filled_, deadline, address_) ==
            ReadStatus::kTimeout) {
          return false;
        }
      }
    } catch (const ConnectionError&) {
      Close();
      throw;
    }
    prefix_filled_ = 0;
    Parse(out);
    return true;
  }

  void set_max_message_bytes(uint32_t bytes) override { max_message_bytes_ = bytes; }
  bool open() const override { return fd_ >= 0; }

  void Close() override {
    if (fd_ >= 0) close(fd_);
    fd_ = -1;
    prefix_filled_ = 0;
    body_filled_ = 0;
  }

 private:
  void Parse(Envelope& out) {
    // Envelope::Clear() would delete the Frame in its oneof. Clearing only
    // the Frame keeps its images' byte buffers and repeated elements
    // allocated, so a frame like the caller's last one parses without
    // touching the heap. Only safe when the new envelope is a frame too,
    // which its first byte tells.
    const bool reuse_frame = out.has_frame() && body_size_ > 0 && static_cast<uint8_t>(buffer_[0]) == kFrameFieldTag;
    if (reuse_frame) {
      out.mutable_frame()->Clear();
    } else {
      out.Clear();
    }
    google::protobuf::io::CodedInputStream input(reinterpret_cast<const uint8_t*>(buffer_.data()),
                                                 static_cast<int>(body_size_));
    if (!out.MergePartialFromCodedStream(&input) || !input.ConsumedEntireMessage()) {
      Fail("sim4cvd sent " + std::to_string(body_size_) + " bytes that are not a valid Envelope");
    }
  }

  [[noreturn]] void Fail(const std::string& what) {
    Close();
    throw ConnectionError(what + " (" + address_ + ")");
  }

  void RequireOpen() const {
    if (fd_ < 0) throw ConnectionError("not connected to sim4cvd at " + address_);
  }

  std::string address_;
  std::string token_;  // Hello.token (AccessToken)
  uint32_t max_message_bytes_;
  int fd_ = -1;
  std::string buffer_;       // body of the envelope being read; only grows
  std::string send_buffer_;  // prefix + body of the envelope being sent
  // Progress of the envelope being read, kept across timeouts.
  uint8_t prefix_[wire::kLengthPrefixBytes] = {};
  std::size_t prefix_filled_ = 0;
  std::size_t body_size_ = 0;
  std::size_t body_filled_ = 0;
};

}  // namespace

std::unique_ptr<Link> OpenTcpLink(const std::string& host, uint16_t port, Deadline deadline,
                                  uint32_t max_message_bytes) {
  return std::make_unique<TcpLink>(host, port, deadline, max_message_bytes);
}

}  // namespace sim4cv::detail
