#include "server/transport/shm/shm_reply_reader.h"

#include <cstring>

#include "server/common/log.h"

namespace sim4cv::transport {

ShmReplyReader::ShmReplyReader(std::shared_ptr<ShmRegion> region, session::Counters& counters,
                               std::chrono::nanoseconds spin)
    : region_(std::move(region)), counters_(counters), spin_(spin) {
  read_ = shm::Atomic(region_->header().reply_read).load(std::memory_order_relaxed);
}

void ShmReplyReader::Drop(uint64_t count) {
  counters_.Add("shm.replies_dropped", count);
  shm::Atomic(region_->header().replies_dropped).fetch_add(count, std::memory_order_relaxed);
}

ShmReplyReader::Result ShmReplyReader::Next(Message& out, Clock::time_point now) {
  shm::ShmHeader& header = region_->header();
  const uint64_t capacity = header.reply_capacity;
  for (;;) {
    shm::Atomic(header.reply_read).store(read_, std::memory_order_relaxed);
    const uint64_t write = shm::Atomic(header.reply_write).load(std::memory_order_acquire);
    if (write - read_ > capacity) {  // producers lapped us: the oldest are overwritten
      Drop(write - capacity - read_);
      read_ = write - capacity;
    }
    if (read_ == write) return Result::kEmpty;
    shm::ShmReplySlot& slot = region_->map().reply_slot(read_);
    const uint64_t state = shm::Atomic(slot.state).load(std::memory_order_acquire);
    const bool claimed = state != 0 && shm::ReplyTicketOf(state) >= read_;
    if (claimed && shm::ReplyTicketOf(state) > read_) {  // a later ticket took the slot
      Drop(1);
      ++read_;
      continue;
    }
    if (!claimed || (state & 1) != 0) {  // reserved, or being written
      if (stalled_ticket_ != read_) {
        stalled_ticket_ = read_;
        stalled_since_ = now;
      }
      if (now - stalled_since_ < kAbandonAfter) return Result::kStalled;
      // The producer died between reserving and finishing. Marking the slot
      // complete makes its late final CAS fail, if it was only slow.
      uint64_t expected = state;
      if (claimed) shm::Atomic(slot.state).compare_exchange_strong(expected, shm::ReplyCompleteState(read_));
      counters_.Add("shm.replies_abandoned");
      LOG_INFO("shared-memory reply " << read_ << " was reserved but not completed within " << kAbandonAfter.count()
                                      << " ms; skipped");
      ++read_;
      continue;
    }
    // Complete: copy, then check the slot was not retaken meanwhile (seqlock).
    const uint64_t token = slot.token;
    const uint32_t size = slot.size;
    const uint32_t checksum = slot.checksum;
    const bool fits = size <= buffer_.size();
    if (fits) std::memcpy(buffer_.data(), slot.data, size);
    std::atomic_thread_fence(std::memory_order_acquire);
    const bool intact = shm::Atomic(slot.state).load(std::memory_order_relaxed) == state;
    ++read_;
    if (!intact) {
      Drop(1);
      continue;
    }
    if (!fits || token == 0 || checksum != shm::ReplyChecksum(token, buffer_.data(), size)) {
      counters_.Add("shm.replies_corrupt");
      LOG_INFO("shared-memory reply " << read_ - 1 << " is corrupt (size " << size << ", token " << token
                                      << ", checksum mismatch or torn write); skipped");
      continue;
    }
    out = {token, buffer_.data(), size};
    return Result::kMessage;
  }
}

uint32_t ShmReplyReader::futex_value() const {
  return shm::Atomic(region_->header().reply_futex).load(std::memory_order_seq_cst);
}

void ShmReplyReader::Wait(uint32_t seen, std::chrono::nanoseconds timeout) {
  shm::ShmHeader& header = region_->header();
  auto futex = shm::Atomic(header.reply_futex);
  // Adaptive part: a reply that follows soon is picked up without a syscall.
  if (spin_.count() > 0) {
    const auto spin_end = Clock::now() + spin_;
    while (Clock::now() < spin_end) {
      if (futex.load(std::memory_order_acquire) != seen) return;
    }
  }
  auto sleeping = shm::Atomic(header.reply_sleeping);
  sleeping.store(1, std::memory_order_seq_cst);
  if (futex.load(std::memory_order_seq_cst) == seen) shm::FutexWait(header.reply_futex, seen, timeout.count());
  sleeping.store(0, std::memory_order_relaxed);
}

void ShmReplyReader::Wake() {
  shm::ShmHeader& header = region_->header();
  shm::Atomic(header.reply_futex).fetch_add(1, std::memory_order_seq_cst);
  shm::FutexWake(header.reply_futex, 1);
}

}  // namespace sim4cv::transport
