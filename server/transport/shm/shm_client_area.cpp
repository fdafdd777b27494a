#include "server/transport/shm/shm_client_area.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cstring>

#include "server/transport/shm/shm_region.h"

namespace sim4cv::transport {

ShmClientArea::ShmClientArea(int socket) : socket_(socket) {
  map_ = shm::AreaMap(CreateSealableMemory("sim4cv-client", shm::kAreaBytes, fd_));
  try {
    // The client may write anything into it, but never change its size: no SIGBUS for the daemon.
    Seal("sim4cv-client", fd_, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_SEAL);
  } catch (...) {
    munmap(map_.base(), shm::kAreaBytes);
    close(fd_);
    throw;
  }
  shm::ShmAreaHeader& h = map_.header();
  h.layout_version = shm::kShmLayoutVersion;
  h.header_bytes = shm::kShmAreaHeaderBytes;
  h.total_bytes = shm::kAreaBytes;
  h.request_offset = shm::kAreaRequestOffset;
  h.request_capacity = shm::kShmRequestCapacity;
  h.request_slot_bytes = shm::kShmRequestSlotBytes;
  h.response_offset = shm::kAreaResponseOffset;
  h.response_depth = shm::kShmResponseDepth;
  h.response_message_bytes = shm::kShmResponseMessageBytes;
  std::memcpy(h.magic, SIM4CV_SHM_AREA_MAGIC, sizeof h.magic);
}

ShmClientArea::~ShmClientArea() {
  munmap(map_.base(), shm::kAreaBytes);
  CloseFd();
}

void ShmClientArea::CloseFd() {
  if (fd_ >= 0) close(fd_);
  fd_ = -1;
}

ShmClientArea::Take ShmClientArea::Next(const uint8_t*& data, uint32_t& size, std::string& why) {
  shm::ShmAreaHeader& h = map_.header();
  const uint64_t write = shm::Atomic(h.request_write).load(std::memory_order_acquire);
  const uint64_t pending = write - read_;  // the client's count, checked before use
  if (pending == 0) return Take::kEmpty;
  if (pending > shm::kShmRequestCapacity) {
    why = "its request_write (" + std::to_string(write) + ") is not within the " +
          std::to_string(shm::kShmRequestCapacity) + " requests after the " + std::to_string(read_) +
          " the daemon has taken (request_read): a client may only write into free request slots";
    return Take::kBroken;
  }
  shm::ShmRequestSlot& slot = map_.request(read_);
  size = shm::Atomic(slot.size).load(std::memory_order_relaxed);  // read once: the client may change it
  if (size > shm::kShmRequestDataBytes) {
    why = "request " + std::to_string(read_) + " claims " + std::to_string(size) + " bytes; a request slot holds " +
          std::to_string(shm::kShmRequestDataBytes);
    return Take::kBroken;
  }
  // Copied before parsing: the client can only tear its own request.
  std::memcpy(buffer_.data(), slot.data, size);
  ++read_;
  shm::Atomic(h.request_read).store(read_, std::memory_order_release);  // the slot is free again
  data = buffer_.data();
  return Take::kMessage;
}

ShmClientArea::Written ShmClientArea::Write(const proto::Envelope& reply) {
  const std::size_t size = reply.ByteSizeLong();
  if (size <= shm::kShmResponseDataBytes) {
    Publish(reply, static_cast<uint32_t>(size), false);
    return Written::kDone;
  }
  if (size > shm::kShmSocketResponseBytes) return Written::kTooLarge;
  // The socket message first: once the ring announces it, it is in the
  // client's receive queue (a Unix socket's send is the peer's receive).
  long_response_.resize(shm::kShmSocketResponseHeaderBytes + size);
  const uint64_t k = written_;  // little-endian, like every shared number
  std::memcpy(long_response_.data(), &k, sizeof k);
  reply.SerializeWithCachedSizesToArray(reinterpret_cast<uint8_t*>(long_response_.data()) + sizeof k);
  // Never waits: a client that leaves its socket full gets an Error instead.
  if (send(socket_, long_response_.data(), long_response_.size(), MSG_DONTWAIT | MSG_NOSIGNAL) !=
      static_cast<ssize_t>(long_response_.size())) {
    return Written::kSocketFull;
  }
  Publish(reply, static_cast<uint32_t>(size), true);
  return Written::kDone;
}

void ShmClientArea::Publish(const proto::Envelope& reply, uint32_t size, bool on_socket) {
  const uint64_t k = written_;
  shm::ShmResponseMessage& message = map_.response(k);
  auto sequence = shm::Atomic(message.sequence);
  sequence.store(shm::ResponseWritingSequence(k), std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
  message.size = size;
  message.on_socket = on_socket ? 1 : 0;
  if (!on_socket) reply.SerializeWithCachedSizesToArray(message.data);
  sequence.store(shm::ResponseCompleteSequence(k), std::memory_order_release);
  written_ = k + 1;
  shm::Atomic(map_.header().responses_written).store(written_, std::memory_order_release);
  shm::StoreAndWake(map_.header().response_futex, ++futex_);
}

void ShmClientArea::MarkClosed() {
  shm::Atomic(map_.header().closed).store(1, std::memory_order_release);
  shm::StoreAndWake(map_.header().response_futex, ++futex_);
}

}  // namespace sim4cv::transport
