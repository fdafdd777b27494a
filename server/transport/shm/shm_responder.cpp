#include "server/transport/shm/shm_responder.h"

namespace sim4cv::transport {

ShmResponder::ShmResponder(std::shared_ptr<ShmRegion> region)
    : region_(std::move(region)), used_(region_->header().response_entries, false) {}

int ShmResponder::Assign(uint64_t token) {
  for (std::size_t i = 0; i < used_.size(); ++i) {
    if (used_[i]) continue;
    used_[i] = true;
    shm::ShmResponseEntry& entry = region_->map().response_entry(static_cast<uint32_t>(i));
    // Reset before publishing the token (release): a client that finds its
    // token sees the fresh count, never the previous owner's responses.
    shm::Atomic(entry.written).store(0, std::memory_order_relaxed);
    shm::Atomic(entry.generation).fetch_add(1, std::memory_order_relaxed);
    shm::Atomic(entry.token).store(token, std::memory_order_release);
    return static_cast<int>(i);
  }
  return -1;
}

void ShmResponder::Free(int entry) {
  if (entry < 0 || static_cast<std::size_t>(entry) >= used_.size()) return;
  used_[static_cast<std::size_t>(entry)] = false;
  shm::Atomic(region_->map().response_entry(static_cast<uint32_t>(entry)).token).store(0, std::memory_order_release);
  WakeAll();
}

bool ShmResponder::Write(int entry_index, const proto::Envelope& reply) {
  const std::size_t size = reply.ByteSizeLong();
  if (size > shm::kShmResponseDataBytes) return false;
  const shm::Mapped& map = region_->map();
  const auto index = static_cast<uint32_t>(entry_index);
  shm::ShmResponseEntry& entry = map.response_entry(index);
  const uint64_t written = shm::Atomic(entry.written).load(std::memory_order_relaxed);
  shm::ShmResponseMessage& message = map.response_message(index, written);
  auto sequence = shm::Atomic(message.sequence);
  const uint64_t before = sequence.load(std::memory_order_relaxed);
  sequence.store(before + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  message.index = written;
  message.size = static_cast<uint32_t>(size);
  reply.SerializeWithCachedSizesToArray(message.data);
  sequence.store(before + 2, std::memory_order_release);
  shm::Atomic(entry.written).store(written + 1, std::memory_order_release);
  shm::ShmHeader& header = region_->header();
  shm::BumpAndWake(header.response_futex, header.response_waiters);
  return true;
}

void ShmResponder::WakeAll() {
  shm::ShmHeader& header = region_->header();
  shm::Atomic(header.response_futex).fetch_add(1, std::memory_order_seq_cst);
  shm::FutexWake(header.response_futex, 0x7fffffff);
}

}  // namespace sim4cv::transport
