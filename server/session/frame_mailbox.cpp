#include "server/session/frame_mailbox.h"

#include "server/session/command_queue.h"

namespace sim4cv::session {

void FrameMailbox::Reset(proto::Delivery delivery, CommandQueue* wake) {
  std::lock_guard lock(mutex_);
  for (auto& f : ring_) f.reset();
  head_ = count_ = 0;
  dropped_ = 0;
  delivery_ = delivery;
  wake_ = wake;
  gate_->full_.store(false, std::memory_order_release);
}

bool FrameMailbox::Offer(const FrameRef& frame) {
  std::lock_guard lock(mutex_);
  const bool lockstep = delivery_ == proto::DELIVERY_LOCKSTEP;
  const std::size_t capacity = lockstep ? kLockstepCapacity : 1;
  bool dropped = false;
  if (count_ == capacity) {
    // Newest-frame rule (and a lockstep overflow, which the scheduler's gate
    // prevents): the oldest waiting frame gives way.
    ring_[head_].reset();
    head_ = (head_ + 1) % ring_.size();
    --count_;
    ++dropped_;
    dropped = true;
  }
  ring_[(head_ + count_) % ring_.size()] = frame;
  ++count_;
  if (lockstep && count_ == capacity) gate_->full_.store(true, std::memory_order_release);
  return dropped;
}

FrameRef FrameMailbox::Take() {
  CommandQueue* wake = nullptr;
  FrameRef frame;
  {
    std::lock_guard lock(mutex_);
    if (count_ == 0) return {};
    frame = std::move(ring_[head_]);
    ring_[head_].reset();
    head_ = (head_ + 1) % ring_.size();
    --count_;
    if (gate_->full_.load(std::memory_order_relaxed)) {
      gate_->full_.store(false, std::memory_order_release);
      wake = wake_;
    }
  }
  // Outside our lock: the queue takes its own.
  if (wake) wake->Wake();
  return frame;
}

uint64_t FrameMailbox::dropped() const {
  std::lock_guard lock(mutex_);
  return dropped_;
}

}  // namespace sim4cv::session
