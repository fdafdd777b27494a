// The daemon's end of the response area: one entry per shared-memory client
// (assigned on its first message, freed when it expires), each a small ring
// of the replies ClientProtocol produced for it (Welcome, Subscribed, State,
// Stats, Error) or the sim thread offered it, written under a per-message
// seqlock. Assign and Free: the shm thread only. Write: any thread, but one
// writer per entry at a time (the entry's ShmClientLink sees to that).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "server/transport/shm/shm_region.h"
#include "sim4cv.pb.h"

namespace sim4cv::transport {

class ShmResponder {
 public:
  explicit ShmResponder(std::shared_ptr<ShmRegion> region);

  // A free entry now owned by `token`, or -1 if all are taken.
  int Assign(uint64_t token);
  // Frees the entry; its client sees its token gone.
  void Free(int entry);
  // Writes `reply` as the entry's next response; false (nothing written) if
  // its encoding exceeds kShmResponseDataBytes.
  bool Write(int entry, const proto::Envelope& reply);
  // Wakes every client waiting for a response (shutdown).
  void WakeAll();

 private:
  std::shared_ptr<ShmRegion> region_;
  std::vector<bool> used_;
};

}  // namespace sim4cv::transport
