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

void UdpPeer::Start() {
  session_ = session::ClientSession::Create(client_, context_, [wakeup = wakeup_] { wakeup->Notify(); });
}

bool UdpPeer::NextFrame() {
  if (frame_in_flight_) return true;
  session::FrameRef frame = session_->NextFrame();
  if (!frame) return false;  // none, or a reply offered before it goes first (the transport's next turn)
  encoder_.Encode(*frame, *session_, false);
  chunker_.Start(frame->frame_id, encoder_.segments(), encoder_.total_size());
  frame_in_flight_ = std::move(frame);
  next_chunk_ = 0;
  return true;
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
  session_->FrameDone();  // sent or lost: either way a lockstep client may Step again
}

void UdpPeer::Close(bool disconnect) {
  frame_in_flight_.reset();
  if (session_) session_->Close(disconnect);
}

}  // namespace sim4cv::transport
