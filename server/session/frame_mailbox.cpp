#include "server/session/frame_mailbox.h"

namespace sim4cv::session {

void FrameMailbox::Reset(proto::Delivery delivery) {
  std::lock_guard lock(mutex_);
  for (auto& f : ring_) f.reset();
  head_ = count_ = 0;
  dropped_ = 0;
  delivery_ = delivery;
}

bool FrameMailbox::Offer(const FrameRef& frame) {
  std::lock_guard lock(mutex_);
  const std::size_t capacity = delivery_ == proto::DELIVERY_LOCKSTEP ? ring_.size() : 1;
  bool dropped = false;
  if (count_ == capacity) {
    // Newest-frame rule (and a lockstep backlog overflow, which the Step limit
    // prevents): the oldest waiting frame gives way.
    ring_[head_].reset();
    head_ = (head_ + 1) % ring_.size();
    --count_;
    ++dropped_;
    dropped = true;
  }
  ring_[(head_ + count_) % ring_.size()] = frame;
  ++count_;
  return dropped;
}

FrameRef FrameMailbox::Take() {
  std::lock_guard lock(mutex_);
  if (count_ == 0) return {};
  FrameRef frame = std::move(ring_[head_]);
  ring_[head_].reset();
  head_ = (head_ + 1) % ring_.size();
  --count_;
  return frame;
}

uint64_t FrameMailbox::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

}  // namespace sim4cv::session
