// Frames waiting to be sent to one client, filled by the sim thread and
// emptied by the client's transport thread. Newest-frame delivery keeps one
// frame and counts each one it replaces as dropped; lockstep delivery queues
// (its backlog is bounded by the client's outstanding Steps).
#pragma once

#include <array>
#include <cstdint>
#include <mutex>

#include "server/session/frame.h"

namespace sim4cv::session {

class FrameMailbox {
 public:
  // Most frames a lockstep client may have outstanding (Steps sent minus
  // frames received); more Steps are refused.
  static constexpr std::size_t kMaxLockstepBacklog = 64;

  // Clears the mailbox and sets the delivery rule (on Subscribe).
  void Reset(proto::Delivery delivery);

  // Sim thread. Returns true if a waiting frame was dropped to make room.
  bool Offer(const FrameRef& frame);
  // Transport thread. The oldest waiting frame, or an empty ref.
  FrameRef Take();

  uint64_t dropped() const;

 private:
  mutable std::mutex mutex_;
  proto::Delivery delivery_ = proto::DELIVERY_NEWEST;
  std::array<FrameRef, kMaxLockstepBacklog> ring_;
  std::size_t head_ = 0, count_ = 0;
  uint64_t dropped_ = 0;
};

}  // namespace sim4cv::session
