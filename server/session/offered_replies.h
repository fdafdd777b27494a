// Replies the sim thread offered one client (ClientLink::OfferReply), waiting
// for that client's transport thread. To keep a reply ahead of the frames
// offered after it, the transport looks here again after it takes a frame
// from the FrameMailbox and before it sends that frame: a reply offered
// before the frame is always found then (the mailbox's mutex orders the two),
// so it can go first.
#pragma once

#include <atomic>
#include <mutex>
#include <vector>

#include "sim4cv.pb.h"

namespace sim4cv::session {

class OfferedReplies {
 public:
  // Sim thread.
  void Offer(proto::Envelope reply) {
    std::lock_guard lock(mutex_);
    replies_.push_back(std::move(reply));
    pending_.store(true, std::memory_order_release);
  }

  // Transport thread. Cheap enough to ask once per frame: no lock.
  bool pending() const { return pending_.load(std::memory_order_acquire); }

  // Transport thread: moves the offered replies, oldest first, into `out`
  // (cleared first). Takes the lock only if something was offered.
  void TakeAll(std::vector<proto::Envelope>& out) {
    out.clear();
    if (!pending()) return;
    std::lock_guard lock(mutex_);
    std::swap(out, replies_);
    pending_.store(false, std::memory_order_relaxed);
  }

 private:
  std::mutex mutex_;
  std::vector<proto::Envelope> replies_;
  std::atomic<bool> pending_{false};
};

}  // namespace sim4cv::session
