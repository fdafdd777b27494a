// Session logic of sim4cv::UdpClient: handshake and requests with retries,
// sequence numbers, keep-alives, and frames put back together from chunks.
#include "sim4cv/udp_client.h"

#include <google/protobuf/io/coded_stream.h>
#include <unistd.h>

#include <algorithm>

#include "frame_reassembler.h"
#include "protocol/framing.h"
#include "../requests.h"
#include "udp_io.h"

namespace sim4cv {
namespace {

using Envelope = proto::Envelope;
using Clock = std::chrono::steady_clock;

// Largest UDP payload; one datagram is read at a time into a buffer this big.
constexpr std::size_t kMaxDatagramBytes = 65536;
// Envelope.sequence: field 100, varint.
constexpr uint32_t kSequenceTag = (Envelope::kSequenceFieldNumber << 3) | 0;
// Unrequested envelopes kept for later (stray replies to retried requests).
constexpr std::size_t kMaxPending = 256;

std::string TimeoutMessage(const char* awaited, std::chrono::milliseconds timeout, const std::string& peer) {
  return "timed out after " + std::to_string(timeout.count()) + " ms waiting for " + awaited +
         " from sim4cvd at UDP " + peer;
}

}  // namespace

UdpClient::UdpClient()
    : reassembler_(std::make_unique<detail::FrameReassembler>(wire::kDefaultMaxMessageBytes)),
      datagram_(kMaxDatagramBytes) {}

UdpClient::~UdpClient() { Close(); }

uint64_t UdpClient::frames_completed() const { return reassembler_->frames_completed(); }
uint64_t UdpClient::frames_dropped_incomplete() const { return reassembler_->frames_dropped_incomplete(); }
uint64_t UdpClient::chunks_ignored() const { return reassembler_->chunks_ignored(); }

void UdpClient::Open(const std::string& host, uint16_t port) {
  Close();
  welcome_.Clear();
  fd_ = detail::udp::Open(host, port, receive_buffer_bytes_);
  peer_ = host + ":" + std::to_string(port);
  reassembler_ = std::make_unique<detail::FrameReassembler>(wire::kDefaultMaxMessageBytes);
  datagrams_malformed_ = 0;
  last_send_ = Clock::now();
}

void UdpClient::Connect(const std::string& host, uint16_t port, const std::string& client_name, Duration timeout,
                        uint32_t protocol_version) {
  const Deadline deadline = Clock::now() + timeout;
  Open(host, port);
  try {
    const Envelope hello = detail::HelloRequest(client_name, protocol_version, detail::AccessToken("udp", host, port));
    Envelope reply;
    if (!Request(hello, Envelope::kWelcome, reply, deadline)) {
      throw ConnectionError(TimeoutMessage("Welcome", timeout, peer_) + " (is that the udp= port of its listening line?)");
    }
    welcome_ = std::move(*reply.mutable_welcome());
  } catch (...) {
    Close();  // a half-done handshake leaves nothing usable
    throw;
  }
}

void UdpClient::Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels,
                          proto::Delivery delivery, bool with_state, Duration timeout) {
  const Envelope request = detail::SubscribeRequest(camera, channels, delivery, with_state);
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_subscribed(); });  // stray answers to retries
  Envelope reply;
  if (!Request(request, Envelope::kSubscribed, reply, Clock::now() + timeout)) {
    throw ConnectionError(TimeoutMessage("Subscribed", timeout, peer_));
  }
  // Frames completed before Subscribed belong to the subscription it replaced.
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_frame(); });
}

void UdpClient::Step() {
  SendEnvelope(detail::StepRequest());
}

bool UdpClient::ReceiveFrame(proto::Frame& frame, Duration timeout) {
  if (!ReceiveKind(Envelope::kFrame, scratch_, Clock::now() + timeout)) return false;
  // Swapping hands the pixels over without a copy; the caller's previous
  // frame comes back into scratch_, whose buffers the next frame reuses.
  frame.Swap(scratch_.mutable_frame());
  return true;
}

bool UdpClient::RequestFrame(proto::Frame& frame, Duration timeout) {
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_frame(); });  // older than asked for
  Envelope request;
  request.mutable_next_frame();
  if (!Request(request, Envelope::kFrame, scratch_, Clock::now() + timeout)) return false;
  frame.Swap(scratch_.mutable_frame());
  return true;
}

void UdpClient::SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence) {
  SendEnvelope(detail::TrackerOutputRequest(frame_id, x, y, width, height, confidence));
}

void UdpClient::SendControls(uint32_t entity_id, float steering, float throttle, float brake) {
  SendEnvelope(detail::ControlsRequest(entity_id, steering, throttle, brake));
}

proto::State UdpClient::GetState(Duration timeout) {
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_state(); });
  Envelope request;
  request.mutable_get_state();
  Envelope reply;
  if (!Request(request, Envelope::kState, reply, Clock::now() + timeout)) {
    throw ConnectionError(TimeoutMessage("State", timeout, peer_));
  }
  return std::move(*reply.mutable_state());
}

proto::Stats UdpClient::GetStats(Duration timeout) {
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_stats(); });
  Envelope request;
  request.mutable_get_stats();
  Envelope reply;
  if (!Request(request, Envelope::kStats, reply, Clock::now() + timeout)) {
    throw ConnectionError(TimeoutMessage("Stats", timeout, peer_));
  }
  return std::move(*reply.mutable_stats());
}

void UdpClient::SendKeepAlive() { SendEnvelope(Envelope()); }

uint64_t UdpClient::SendEnvelope(const Envelope& envelope) {
  const uint64_t sequence = next_sequence_++;
  SendEnvelope(envelope, sequence);
  return sequence;
}

void UdpClient::SendEnvelope(const Envelope& envelope, uint64_t sequence) {
  send_buffer_.clear();
  envelope.AppendToString(&send_buffer_);
  if (sequence != 0) {
    // Appended after the message: protobuf lets a later value of a field win.
    uint8_t field[16];
    uint8_t* end = google::protobuf::io::CodedOutputStream::WriteVarint32ToArray(kSequenceTag, field);
    end = google::protobuf::io::CodedOutputStream::WriteVarint64ToArray(sequence, end);
    send_buffer_.append(reinterpret_cast<const char*>(field), static_cast<std::size_t>(end - field));
  }
  SendRaw(send_buffer_.data(), send_buffer_.size());
}

void UdpClient::SendRaw(const void* data, std::size_t size) {
  RequireConnected();
  try {
    detail::udp::Send(fd_, data, size, peer_);
  } catch (const ConnectionError&) {
    Close();
    throw;
  }
  last_send_ = Clock::now();
}

bool UdpClient::ReceiveEnvelope(Envelope& envelope, Duration timeout) {
  if (!pending_.empty()) {
    envelope.Swap(&pending_.front());
    pending_.pop_front();
    return true;
  }
  if (!ReadEnvelope(Clock::now() + timeout)) return false;
  envelope.Swap(&scratch_);
  return true;
}

void UdpClient::Close() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
  pending_.clear();
  reassembler_->Reset();
}

bool UdpClient::Request(const Envelope& request, Envelope::KindCase kind, Envelope& out, Deadline deadline) {
  while (true) {
    SendEnvelope(request);
    const Deadline retry = std::min(deadline, Clock::now() + retry_interval_);
    if (ReceiveKind(kind, out, retry)) return true;
    if (Clock::now() >= deadline) return false;
  }
}

bool UdpClient::ReceiveKind(Envelope::KindCase kind, Envelope& out, Deadline deadline) {
  if (detail::TakeQueued(pending_, kind, out)) return true;
  while (ReadEnvelope(deadline)) {
    if (scratch_.kind_case() == kind) {
      if (&out != &scratch_) out.Swap(&scratch_);
      return true;
    }
    if (scratch_.has_error()) ThrowServerError(scratch_.error());
    // Only Connect asks for a Welcome; one arriving later answers a Hello it repeated.
    if (scratch_.has_welcome()) continue;
    if (pending_.size() >= kMaxPending) pending_.pop_front();
    pending_.push_back(std::move(scratch_));
  }
  return false;
}

bool UdpClient::ReadEnvelope(Deadline deadline) {
  RequireConnected();
  while (true) {
    // Wake up for keep-alives too, so a client that only receives stays registered.
    if (Clock::now() - last_send_ >= keepalive_interval_) SendKeepAlive();
    const Deadline wake = std::min(deadline, last_send_ + keepalive_interval_);
    long size = -1;
    try {
      size = detail::udp::Receive(fd_, datagram_.data(), datagram_.size(), wake, peer_);
    } catch (const ConnectionError&) {
      Close();
      throw;
    }
    if (size < 0) {
      if (Clock::now() >= deadline) return false;
      continue;
    }
    detail::ChunkView chunk;
    switch (detail::ClassifyDatagram(datagram_.data(), static_cast<std::size_t>(size), chunk)) {
      case detail::DatagramKind::kChunk:
        if (reassembler_->Add(chunk) == detail::FrameReassembler::Result::kComplete && ParseFrame()) return true;
        break;
      case detail::DatagramKind::kOther:
        scratch_.Clear();
        if (scratch_.ParseFromArray(datagram_.data(), static_cast<int>(size))) return true;
        ++datagrams_malformed_;
        break;
      case detail::DatagramKind::kMalformed: ++datagrams_malformed_; break;
    }
  }
}

bool UdpClient::ParseFrame() {
  const std::string_view bytes = reassembler_->frame();
  // Envelope::Clear() would delete the Frame in its oneof; clearing only the
  // Frame keeps its buffers, so a frame like the last one parses without
  // touching the heap.
  if (scratch_.has_frame()) {
    scratch_.mutable_frame()->Clear();
    scratch_.clear_sequence();
  } else {
    scratch_.Clear();
  }
  google::protobuf::io::CodedInputStream input(reinterpret_cast<const uint8_t*>(bytes.data()),
                                               static_cast<int>(bytes.size()));
  if (scratch_.MergePartialFromCodedStream(&input) && input.ConsumedEntireMessage() && scratch_.has_frame()) {
    return true;
  }
  ++datagrams_malformed_;
  return false;
}

void UdpClient::ThrowServerError(const proto::Error& error) {
  if (error.fatal()) Close();
  throw ServerError(error.code(), error.message(), error.fatal());
}

void UdpClient::RequireConnected() const {
  if (fd_ < 0) throw ConnectionError("not connected to sim4cvd" + (peer_.empty() ? "" : " at UDP " + peer_));
}

}  // namespace sim4cv
