// Fuzz target: the daemon's reader of a shared-memory client's request ring
// (server/transport/shm/shm_client_area.cpp, ShmClientArea::Next), after the
// client has stored anything anywhere it may write. The input is laid over the
// area's header and request slots (what the client maps read-write); the
// daemon then takes requests until the ring is empty or broken, parses each as
// the shm thread does, and writes a response, which must not trust anything
// the client stored either.
//
// One area serves the whole process: creating, sealing, mapping and unmapping
// a memfd per input cost more than everything the reader does. Each input
// starts from the client bytes the constructor left (a copy taken once), and
// is laid over them shifted by the requests the area has already taken (its
// own count, request_read): request_write plus that count, input slot j in
// ring slot (count + j). The reader sees exactly what a fresh area holding the
// input would show it, since it reads nothing of the client's but
// request_write and the slots (the responses it writes go to the daemon's own
// ring and counters, which it never reads back).
// Kept to one file: the shm layout is still changing (see docs/protocol.md §13).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "server/transport/shm/shm_client_area.h"

namespace {

using sim4cv::transport::ShmClientArea;
namespace shm = sim4cv::shm;
// The part of the area a client writes: the header and the request slots.
constexpr std::size_t kClientBytes = shm::kAreaRequestOffset + std::size_t{shm::kShmRequestCapacity} * shm::kShmRequestSlotBytes;

class ReusedArea {
 public:
  ReusedArea() : fresh_(area_.map().base(), area_.map().base() + kClientBytes) {}

  ShmClientArea& area() { return area_; }

  // The area as a fresh one holding `data` would look to the reader.
  void Load(const uint8_t* data, std::size_t size) {
    uint8_t* base = area_.map().base();
    std::memcpy(base, fresh_.data(), kClientBytes);
    std::memcpy(base, data, std::min<std::size_t>(size, shm::kAreaRequestOffset));
    auto& write = area_.map().header().request_write;
    write += taken_;  // the input's count, relative to what the area has taken
    for (std::size_t j = 0; j < shm::kShmRequestCapacity; ++j) {
      const std::size_t at = shm::kAreaRequestOffset + j * shm::kShmRequestSlotBytes;
      if (at >= size) break;
      std::memcpy(&area_.map().request(taken_ + j), data + at, std::min<std::size_t>(size - at, shm::kShmRequestSlotBytes));
    }
  }

  // The reader took one more request (it counts them the same way).
  void Took() { ++taken_; }
  uint64_t taken() const { return taken_; }

 private:
  ShmClientArea area_{-1};  // no socket: every reply written here fits the response ring
  std::vector<uint8_t> fresh_;
  uint64_t taken_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static ReusedArea reused;
  reused.Load(data, size);
  ShmClientArea& area = reused.area();
  sim4cv::proto::Envelope request, reply;
  reply.mutable_error()->set_message("a reply");
  const uint8_t* message = nullptr;
  uint32_t message_size = 0;
  std::string why;
  // At most one turn over the ring: the daemon's own count bounds the loop.
  uint32_t taken = 0;
  for (; taken <= shm::kShmRequestCapacity; ++taken) {
    const ShmClientArea::Take take = area.Next(message, message_size, why);
    if (take != ShmClientArea::Take::kMessage) break;
    reused.Took();
    if (message_size > shm::kShmRequestDataBytes) __builtin_trap();
    if (request.ParseFromArray(message, static_cast<int>(message_size))) (void)area.Write(reply);
  }
  // The reader publishes its count: the shift above must be the one it uses.
  if (taken > 0 && area.map().header().request_read != reused.taken()) __builtin_trap();
  (void)area.Write(reply);
  area.MarkClosed();
  return 0;
}
