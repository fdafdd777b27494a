// Frames waiting to be sent to one client, filled by the sim thread and
// emptied by the client's transport thread. Newest-frame delivery keeps one
// frame and counts each one it replaces as dropped; lockstep delivery queues
// at most limits::kLockstepFramesQueued frames, and while its queue is full
// the client is not ready (MailboxGate): the scheduler renders no further
// frame for it until it reads one.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>

#include "server/common/limits.h"
#include "server/session/frame.h"

namespace sim4cv::session {

class CommandQueue;

// What the sim thread sees of a lockstep client's mailbox: whether it is
// full. Shared (the scheduler's subscription and the session each keep it
// alive, whichever goes first). When a full mailbox gives up a frame, the
// mailbox wakes the sim thread through the queue it was given, so a lockstep
// simulation held back by this client goes on at once.
class MailboxGate {
 public:
  bool full() const { return full_.load(std::memory_order_acquire); }

 private:
  friend class FrameMailbox;
  std::atomic<bool> full_{false};
};

class FrameMailbox {
 public:
  // Steps a lockstep client may have outstanding (limits::kMaxOutstandingSteps).
  static constexpr std::size_t kMaxLockstepBacklog = limits::kMaxOutstandingSteps;
  // Frames a lockstep mailbox holds; it is full (not ready) at this many.
  static constexpr std::size_t kLockstepCapacity = limits::kLockstepFramesQueued;

  FrameMailbox() : gate_(std::make_shared<MailboxGate>()) {}

  // Clears the mailbox and sets the delivery rule (on Subscribe). `wake`, if
  // given, is woken when a full lockstep mailbox gives up a frame.
  void Reset(proto::Delivery delivery, CommandQueue* wake = nullptr);

  // Sim thread. Returns true if a waiting frame was dropped to make room
  // (newest delivery; a lockstep client is not offered frames while full).
  bool Offer(const FrameRef& frame);
  // Transport thread. The oldest waiting frame, or an empty ref.
  FrameRef Take();

  uint64_t dropped() const;
  // For the scheduler's subscription (SubscribeCommand::gate).
  std::shared_ptr<const MailboxGate> gate() const { return gate_; }

 private:
  static constexpr std::size_t kRingSize = kLockstepCapacity > 1 ? kLockstepCapacity : 1;

  mutable std::mutex mutex_;
  proto::Delivery delivery_ = proto::DELIVERY_NEWEST;
  std::array<FrameRef, kRingSize> ring_;
  std::size_t head_ = 0, count_ = 0;
  uint64_t dropped_ = 0;
  CommandQueue* wake_ = nullptr;
  const std::shared_ptr<MailboxGate> gate_;
};

}  // namespace sim4cv::session
