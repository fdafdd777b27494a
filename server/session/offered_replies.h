// Replies the sim thread offered one client (ClientLink::OfferReply), waiting
// for that client's transport thread. To keep a reply ahead of the frames
// offered after it, the transport looks here again after it takes a frame
// from the FrameMailbox and before it sends that frame: a reply offered
// before the frame is always found then (the mailbox's mutex orders the two),
// so it can go first.
//
// Bounded in bytes (limits::kMaxOfferedReplyBytes): the sim thread answers
// requests the transport already read, so a client that pipelines requests
// the sim thread refuses or answers at length, and never reads, could grow it
// without end. Past the bound the waiting replies are dropped and only a
// fatal Error naming the limit is left for the transport, which sends it and
// closes the client as after any fatal Error.
#pragma once

#include <atomic>
#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include "server/common/limits.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

class OfferedReplies {
 public:
  explicit OfferedReplies(std::size_t max_bytes = limits::kMaxOfferedReplyBytes) : max_bytes_(max_bytes) {}

  // Sim thread. False if the reply was dropped: the bound was reached (now or
  // before), and the client is being closed.
  bool Offer(proto::Envelope reply) {
    const std::size_t size = reply.ByteSizeLong();
    std::lock_guard lock(mutex_);
    if (overflowed_) return false;
    if (bytes_ + size > max_bytes_) {
      Overflow(size);
      return false;
    }
    bytes_ += size;
    bytes_waiting_.store(bytes_, std::memory_order_relaxed);
    replies_.push_back(std::move(reply));
    pending_.store(true, std::memory_order_release);
    return true;
  }

  // Transport thread. Cheap enough to ask once per frame: no lock.
  bool pending() const { return pending_.load(std::memory_order_acquire); }
  // Transport thread: serialized bytes waiting here (for back-pressure).
  std::size_t bytes() const { return bytes_waiting_.load(std::memory_order_relaxed); }

  // Transport thread: moves the offered replies, oldest first, into `out`
  // (cleared first). Takes the lock only if something was offered. After an
  // overflow `out` holds the fatal Error alone, once.
  void TakeAll(std::vector<proto::Envelope>& out) {
    out.clear();
    if (!pending()) return;
    std::lock_guard lock(mutex_);
    std::swap(out, replies_);
    bytes_ = 0;
    bytes_waiting_.store(0, std::memory_order_relaxed);
    pending_.store(false, std::memory_order_relaxed);
    // A burst's slots go back with the burst.
    if (replies_.capacity() > kKeptReplies) std::vector<proto::Envelope>().swap(replies_);
  }

 private:
  static constexpr std::size_t kKeptReplies = 64;

  // Under the lock: drop what waits (the client is closed anyway) and leave the Error.
  void Overflow(std::size_t size) {
    overflowed_ = true;
    std::vector<proto::Envelope>().swap(replies_);
    proto::Envelope error;
    error.mutable_error()->set_code(proto::ERROR_CODE_INVALID_STATE);
    error.mutable_error()->set_fatal(true);
    error.mutable_error()->set_message(
        "the daemon's answers waiting to be sent to this client reached " + std::to_string(bytes_ + size) +
        " bytes, over the limit of " + std::to_string(max_bytes_) +
        " (kMaxOfferedReplyBytes): the client sends requests faster than it reads their answers; read "
        "Configured and Error answers as they come, or send fewer requests");
    replies_.push_back(std::move(error));
    bytes_ = replies_.back().ByteSizeLong();
    bytes_waiting_.store(bytes_, std::memory_order_relaxed);
    pending_.store(true, std::memory_order_release);
  }

  const std::size_t max_bytes_;
  std::mutex mutex_;
  std::vector<proto::Envelope> replies_;
  std::size_t bytes_ = 0;  // under mutex_
  bool overflowed_ = false;
  std::atomic<std::size_t> bytes_waiting_{0};
  std::atomic<bool> pending_{false};
};

}  // namespace sim4cv::session
