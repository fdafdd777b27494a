// The daemon's frame object: a memfd holding the header and the frame slots,
// created, reserved, mapped read-write and filled here, then sealed so that
// nobody can shrink or grow it and no one else can ever map it writable
// (F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_FUTURE_WRITE | F_SEAL_SEAL). Clients
// get its descriptor over the Unix socket (ShmListener) and map it
// read-only; the daemon's own mapping stays writable. The geometry is the
// daemon's own copy: nothing is ever read back from the object to find an
// address.
#pragma once

#include <cstdint>
#include <string>

#include "protocol/shm_sync.h"

namespace sim4cv::transport {

// The ring's channels unless --shm-channels says otherwise: what a tracker or
// detector reads. All six would make each slot 3.3x larger.
inline constexpr channels::ChannelSet kShmDefaultChannels =
    channels::Bit(proto::CHANNEL_RGB) | channels::Bit(proto::CHANNEL_DEPTH) | channels::Bit(proto::CHANNEL_MASK);

struct ShmRegionParams {
  std::string camera_name;
  uint32_t width = 0, height = 0;
  uint32_t slot_count = 8;
  uint32_t expiry_ms = 5000;
  // Bit (1 << proto::Channel) per pixel channel the slots carry (--shm-channels).
  channels::ChannelSet channel_mask = kShmDefaultChannels;
};

class ShmRegion {
 public:
  // Throws std::runtime_error naming the failing call, std::invalid_argument for bad parameters.
  explicit ShmRegion(const ShmRegionParams& params);
  ~ShmRegion();  // unmaps and closes; clients keep their own mappings
  ShmRegion(const ShmRegion&) = delete;
  ShmRegion& operator=(const ShmRegion&) = delete;

  // The sealed memfd, to hand to clients (they map it read-only).
  int fd() const { return fd_; }
  const shm::FrameMap& map() const { return map_; }
  shm::ShmHeader& header() const { return map_.header(); }
  const shm::Geometry& geometry() const { return map_.geometry(); }
  const ShmRegionParams& params() const { return params_; }

 private:
  ShmRegionParams params_;
  shm::FrameMap map_;
  int fd_ = -1;
};

// Creates a memfd of `bytes`, reserves its memory (a full tmpfs fails here,
// not as SIGBUS later), maps it read-write (MAP_POPULATE: no page faults on
// the sim thread later) and returns the mapping; `fd` receives the
// descriptor, still unsealed. Throws std::runtime_error naming `what`.
void* CreateSealableMemory(const char* what, uint64_t bytes, int& fd);
// Adds `seals` (F_SEAL_*) to `fd`; throws std::runtime_error naming `what`.
void Seal(const char* what, int fd, int seals);

}  // namespace sim4cv::transport
