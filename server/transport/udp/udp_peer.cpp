#include "server/transport/udp/udp_peer.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace sim4cv::transport {
namespace {

// Errors one client may be sent: a burst of 20, then 20 per second.
constexpr double kErrorsPerSecond = 20;
constexpr double kErrorBurst = 20;

}  // namespace

Wakeup::Wakeup() : fd_(eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC)) {
  if (fd_ < 0) throw std::runtime_error(std::string("cannot create an eventfd: ") + std::strerror(errno));
}

Wakeup::~Wakeup() { close(fd_); }

void Wakeup::Notify() {
  if (pending_.exchange(true)) return;
  const uint64_t one = 1;
  // Non-blocking: a full counter (never in practice) already means "wake up".
  [[maybe_unused]] const ssize_t wrote = write(fd_, &one, sizeof one);
}

void Wakeup::Clear() {
  uint64_t value = 0;
  [[maybe_unused]] const ssize_t got = read(fd_, &value, sizeof value);
  pending_.store(false);
}

UdpPeer::UdpPeer(session::ClientId client, const PeerAddress& address, const session::ServerContext& context,
                 std::shared_ptr<Wakeup> wakeup, std::size_t max_datagram_bytes, Clock::time_point now)
    : client_(client),
      address_(address),
      context_(context),
      wakeup_(std::move(wakeup)),
      error_limit_(kErrorsPerSecond, kErrorBurst),
      last_heard_(now),
      chunker_(max_datagram_bytes) {}

void UdpPeer::Start() { protocol_ = std::make_unique<session::ClientProtocol>(client_, context_, shared_from_this(), mailbox_); }

void UdpPeer::OfferFrame(const session::FrameRef& frame) {
  if (closed_) return;
  mailbox_.Offer(frame);
  wakeup_->Notify();
}

void UdpPeer::OfferReply(proto::Envelope reply) {
  if (closed_) return;  // unregistered: nobody to answer
  offered_replies_.Offer(std::move(reply));
  wakeup_->Notify();
}

bool UdpPeer::NextFrame() {
  while (!frame_in_flight_) {
    session::FrameRef frame = mailbox_.Take();
    if (!frame) return false;
    // A frame of the camera this client subscribed to before a re-subscribe is stale.
    if (!protocol_->subscribed() || frame->camera_index != protocol_->camera_index()) continue;
    encoder_.Encode(*frame, frame->camera_name, protocol_->subscription(), protocol_->with_state(),
                    mailbox_.dropped(), false);
    chunker_.Start(frame->frame_id, encoder_.segments(), encoder_.total_size());
    frame_in_flight_ = std::move(frame);
    next_chunk_ = 0;
  }
  // Before the first chunk: a reply offered before this frame may have
  // arrived since the transport's last look, and it goes first.
  return next_chunk_ > 0 || !offered_replies_.pending();
}

bool UdpPeer::Advance(uint32_t count) {
  next_chunk_ += count;
  if (next_chunk_ < chunker_.chunk_count()) return false;
  EndFrame();
  return true;
}

void UdpPeer::AbandonFrame() {
  if (frame_in_flight_) EndFrame();
}

void UdpPeer::EndFrame() {
  frame_in_flight_.reset();
  next_chunk_ = 0;
  protocol_->OnFrameSent();  // sent or lost: either way a lockstep client may Step again
}

void UdpPeer::Close(bool disconnect) {
  if (closed_.exchange(true)) return;
  if (disconnect) protocol_->Disconnect();
  protocol_.reset();  // breaks the peer -> protocol -> peer cycle
  frame_in_flight_.reset();
  mailbox_.Reset(proto::DELIVERY_NEWEST);  // release frames back to the pool now
}

}  // namespace sim4cv::transport
