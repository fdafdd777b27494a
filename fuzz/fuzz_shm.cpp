// Fuzz target: the daemon's reader of a shared-memory client's request ring
// (server/transport/shm/shm_client_area.cpp, ShmClientArea::Next), after the
// client has stored anything anywhere it may write. The input is copied over
// the start of a fresh area (its header and request slots, as the client maps
// them read-write); the daemon then takes requests until the ring is empty or
// broken, parses each as the shm thread does, and writes a response, which
// must not trust anything the client stored either.
// Kept to one file: the shm layout is still changing (see docs/protocol.md §13).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "fuzz/fuzz_input.h"
#include "server/transport/shm/shm_client_area.h"

namespace {

using sim4cv::transport::ShmClientArea;
// The part of the area a client writes: the header and the request slots.
constexpr std::size_t kClientBytes = sim4cv::shm::kAreaRequestOffset +
                                     std::size_t{sim4cv::shm::kShmRequestCapacity} * sim4cv::shm::kShmRequestSlotBytes;

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  ShmClientArea area(-1);  // no socket: every reply written here fits the response ring
  std::memcpy(area.map().base(), data, std::min(size, kClientBytes));
  sim4cv::proto::Envelope request, reply;
  reply.mutable_error()->set_message("a reply");
  const uint8_t* message = nullptr;
  uint32_t message_size = 0;
  std::string why;
  // At most one turn over the ring: the daemon's own count bounds the loop.
  for (uint32_t taken = 0; taken <= sim4cv::shm::kShmRequestCapacity; ++taken) {
    const ShmClientArea::Take take = area.Next(message, message_size, why);
    if (take != ShmClientArea::Take::kMessage) break;
    if (message_size > sim4cv::shm::kShmRequestDataBytes) __builtin_trap();
    if (request.ParseFromArray(message, static_cast<int>(message_size))) (void)area.Write(reply);
  }
  (void)area.Write(reply);
  area.MarkClosed();
  return 0;
}
