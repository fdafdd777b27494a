// sim4cv::Client, the facade: handshake, requests matched to their answers
// (retried over lossy links), queues and the frame path, the same over every
// transport. Moving bytes is each transport's Link (link.h).
#include "sim4cv/client.h"

#include <algorithm>

#include "link.h"
#include "requests.h"
#include "sim4cv/shm_client.h"
#include "sim4cv/udp_client.h"

namespace sim4cv {
namespace {

using Envelope = proto::Envelope;
using Clock = std::chrono::steady_clock;

Clock::time_point DeadlineAfter(Client::Duration timeout) { return Clock::now() + timeout; }

// Envelopes kept for later while waiting for another kind; over a lossy link
// stray answers to retried requests would otherwise pile up.
constexpr std::size_t kMaxPending = 256;

}  // namespace

ServerError::ServerError(proto::ErrorCode code, const std::string& message, bool fatal, uint32_t request_id)
    : std::runtime_error(message), code_(code), fatal_(fatal), request_id_(request_id) {}

std::optional<ImageView> FindImage(const proto::Frame& frame, proto::Channel channel) {
  for (const proto::Image& image : frame.images()) {
    if (image.channel() != channel) continue;
    // A view that promises more bytes than the frame holds would let callers
    // read past the buffer, so a short image is a broken peer, not a view.
    if (image.data().size() < static_cast<std::size_t>(image.stride()) * frame.height()) {
      throw ConnectionError("frame " + std::to_string(frame.frame_id()) + ": " + proto::Channel_Name(channel) +
                            " carries " + std::to_string(image.data().size()) + " bytes, fewer than stride " +
                            std::to_string(image.stride()) + " x height " + std::to_string(frame.height()));
    }
    return ImageView{reinterpret_cast<const uint8_t*>(image.data().data()),
                     frame.width(),
                     frame.height(),
                     image.stride(),
                     image.format(),
                     image.element(),
                     image.components()};
  }
  return std::nullopt;
}

Client::Client() = default;
Client::~Client() { Close(); }

void Client::Connect(const std::string& address, const std::string& client_name, Duration timeout,
                     uint32_t protocol_version) {
  // One deadline for connecting and the handshake: the caller's timeout
  // bounds the whole call.
  const Deadline deadline = DeadlineAfter(timeout);
  Close();
  welcome_.Clear();
  address_ = address;
  link_ = detail::OpenLink(address, deadline, max_message_bytes_);
  try {
    welcome_ = link_->Hello(client_name, protocol_version, deadline);
  } catch (...) {
    Close();  // a half-done handshake leaves nothing usable
    throw;
  }
}

void Client::Connect(const std::string& host, uint16_t port, const std::string& client_name, Duration timeout,
                     uint32_t protocol_version) {
  Connect("tcp://" + host + ":" + std::to_string(port), client_name, timeout, protocol_version);
}

void Client::ConnectRaw(const std::string& host, uint16_t port, Duration timeout) {
  Close();
  welcome_.Clear();
  address_ = "tcp://" + host + ":" + std::to_string(port);
  link_ = detail::OpenTcpLink(host, port, DeadlineAfter(timeout), max_message_bytes_);
}

bool Client::connected() const { return link_ && link_->open(); }
UdpClient* Client::udp() { return link_ ? link_->udp() : nullptr; }
ShmClient* Client::shm() { return link_ ? link_->shm() : nullptr; }

void Client::set_max_message_bytes(uint32_t bytes) {
  max_message_bytes_ = bytes;
  if (link_) link_->set_max_message_bytes(bytes);
}

void Client::Subscribe(const std::string& camera, const std::vector<proto::Channel>& channels, proto::Delivery delivery,
                       bool with_state, Duration timeout) {
  const Deadline deadline = DeadlineAfter(timeout);
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_subscribed(); });  // stray answers to retries
  Envelope reply;
  if (!Request(link(), detail::SubscribeRequest(camera, channels, delivery, with_state),
               {[](const Envelope& e) { return e.has_subscribed(); }}, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) + " ms waiting for Subscribed from " +
                          address_);
  }
  // The daemon sends Subscribed before any frame of the new subscription, so
  // every frame queued by now belongs to the one it replaced.
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_frame(); });
}

void Client::Step() { link().Send(detail::StepRequest()); }

bool Client::ReceiveFrame(proto::Frame& frame, Duration timeout) {
  if (!ReceiveMatching(link(), {[](const Envelope& e) { return e.has_frame(); }, true, true}, scratch_,
                       DeadlineAfter(timeout))) {
    return false;
  }
  // Swapping hands the pixels over without a copy and leaves the caller's
  // previous frame in scratch_, whose buffers the next parse fills in place.
  frame.Swap(scratch_.mutable_frame());
  return true;
}

const proto::Frame& Client::StepAndReceive(Duration timeout) {
  Step();
  if (!ReceiveFrame(frame_, timeout)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) + " ms waiting for a Frame from " +
                          address_);
  }
  return frame_;
}

const proto::Frame& Client::RequestFrame(Duration timeout) {
  std::erase_if(pending_, [](const Envelope& queued) { return queued.has_frame(); });  // older than asked for
  Envelope request;
  request.mutable_next_frame();
  if (!Request(link(), request, {[](const Envelope& e) { return e.has_frame(); }, true, true}, scratch_,
               DeadlineAfter(timeout))) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) +
                          " ms waiting for a requested Frame from " + address_);
  }
  frame_.Swap(scratch_.mutable_frame());
  return frame_;
}

void Client::SendTrackerOutput(uint64_t frame_id, float x, float y, float width, float height, float confidence) {
  link().Send(detail::TrackerOutputRequest(frame_id, x, y, width, height, confidence));
}

void Client::SendControls(uint32_t entity_id, float steering, float throttle, float brake) {
  link().Send(detail::ControlsRequest(entity_id, steering, throttle, brake));
}

proto::State Client::GetState(Duration timeout) {
  const Deadline deadline = DeadlineAfter(timeout);
  const auto state = [](const Envelope& e) { return e.has_state(); };
  Envelope reply;
  // A queued State answers a request already made; asking again would leave
  // every later GetState one answer behind. Over a lossy link it may be a
  // late answer to a retry: stale.
  if (link().retry_interval().count() > 0) std::erase_if(pending_, state);
  if (!detail::TakeQueuedIf(pending_, state, reply)) {
    Envelope request;
    request.mutable_get_state();
    if (!Request(link(), request, {state}, reply, deadline)) {
      throw ConnectionError("timed out after " + std::to_string(timeout.count()) + " ms waiting for State from " +
                            address_);
    }
  }
  return std::move(*reply.mutable_state());
}

proto::Stats Client::GetStats(Duration timeout) {
  const auto stats = [](const Envelope& e) { return e.has_stats(); };
  std::erase_if(pending_, stats);
  Envelope request;
  request.mutable_get_stats();
  Envelope reply;
  if (!Request(link(), request, {stats}, reply, DeadlineAfter(timeout))) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) + " ms waiting for Stats from " +
                          address_);
  }
  return std::move(*reply.mutable_stats());
}

proto::Configured Client::Configure(proto::Configure request, Duration timeout) {
  const Deadline deadline = DeadlineAfter(timeout);
  if (++last_request_id_ == 0) ++last_request_id_;  // 0 could not be told apart from other Errors
  const uint32_t id = last_request_id_;
  request.set_request_id(id);
  Envelope envelope;
  *envelope.mutable_configure() = std::move(request);
  const auto answer = [id](const Envelope& e) {
    return (e.has_configured() && e.configured().request_id() == id) || (e.has_error() && e.error().request_id() == id);
  };
  Envelope reply;
  if (!Request(link().configure_link(), envelope, {answer, /*errors_interrupt=*/false}, reply, deadline)) {
    throw ConnectionError("timed out after " + std::to_string(timeout.count()) + " ms waiting for Configured from " +
                          address_);
  }
  if (reply.has_error()) ThrowServerError(reply.error());
  return std::move(*reply.mutable_configured());
}

void Client::SendEnvelope(const Envelope& envelope) { link().Send(envelope); }

void Client::SendRaw(const void* data, std::size_t size) { link().SendRaw(data, size); }

bool Client::ReceiveEnvelope(Envelope& envelope, Duration timeout) {
  if (!pending_.empty()) {
    envelope.Swap(&pending_.front());
    pending_.pop_front();
    return true;
  }
  return link().Receive(envelope, DeadlineAfter(timeout), /*frame_wanted=*/true);
}

void Client::Close() {
  if (link_) link_->Close();
  link_.reset();
  pending_.clear();
}

bool Client::ReceiveKind(Envelope::KindCase kind, Envelope& out, Deadline deadline) {
  return ReceiveMatching(link(), {[kind](const Envelope& e) { return e.kind_case() == kind; }}, out, deadline);
}

bool Client::Request(detail::Link& link, const Envelope& request, const Awaited& awaited, Envelope& out,
                     Deadline deadline) {
  const auto retry = link.retry_interval();
  for (;;) {
    link.Send(request);
    const Deadline slice = retry.count() > 0 ? std::min(deadline, Clock::now() + retry) : deadline;
    if (ReceiveMatching(link, awaited, out, slice)) return true;
    if (Clock::now() >= deadline) return false;
  }
}

bool Client::ReceiveMatching(detail::Link& link, const Awaited& awaited, Envelope& out, Deadline deadline) {
  // Only Configure queues Errors (those that are not its answer); whoever
  // waits next meets them in arrival order.
  const auto stops = [&](const Envelope& e) {
    return awaited.wanted(e) || (awaited.errors_interrupt && e.has_error());
  };
  if (detail::TakeQueuedIf(pending_, stops, out)) {
    if (!awaited.wanted(out)) ThrowServerError(out.error());
    return true;
  }
  while (link.Receive(scratch_, deadline, awaited.frame)) {
    if (awaited.wanted(scratch_)) {
      if (&out != &scratch_) out.Swap(&scratch_);
      return true;
    }
    if (scratch_.has_error() && (awaited.errors_interrupt || scratch_.error().fatal())) {
      ThrowServerError(scratch_.error());
    }
    if (pending_.size() >= kMaxPending) pending_.pop_front();
    pending_.push_back(std::move(scratch_));
  }
  return false;
}

void Client::ThrowServerError(const proto::Error& error) {
  if (error.fatal()) Close();
  throw ServerError(error.code(), error.message(), error.fatal(), error.request_id());
}

detail::Link& Client::link() const {
  if (!link_ || !link_->open()) {
    throw ConnectionError("not connected to sim4cvd" + (address_.empty() ? "" : " at " + address_));
  }
  return *link_;
}

}  // namespace sim4cv
