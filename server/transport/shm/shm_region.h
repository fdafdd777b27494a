// The daemon's side of the shared-memory object: creates it (replacing a
// stale one left by a crashed daemon), sizes, maps and initialises it, and
// removes its name on Unlink. The mapping lives as long as the last holder
// (the transport, or the ring writer the sim thread may still hold).
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <string>

#include "protocol/shm_sync.h"

namespace sim4cv::transport {

struct ShmRegionParams {
  std::string name;  // "/name"
  std::string camera_name;
  uint32_t width = 0, height = 0;
  uint32_t slot_count = 8;
  uint32_t reply_capacity = 256;
  uint32_t response_entries = 64;
  uint32_t expiry_ms = 5000;
  // Bit (1 << proto::Channel) per pixel channel the slots carry (--shm-channels).
  uint32_t channel_mask = shm::kShmAllPixelChannels;
};

class ShmRegion {
 public:
  // Throws std::runtime_error naming the object and the failing call.
  explicit ShmRegion(const ShmRegionParams& params);
  ~ShmRegion();  // unmaps; the name stays until Unlink
  ShmRegion(const ShmRegion&) = delete;
  ShmRegion& operator=(const ShmRegion&) = delete;

  // Removes the name (idempotent); clients that mapped it keep their mapping.
  void Unlink();

  const shm::Mapped& map() const { return map_; }
  shm::ShmHeader& header() const { return map_.header(); }
  const shm::Geometry& geometry() const { return geometry_; }
  const ShmRegionParams& params() const { return params_; }

 private:
  ShmRegionParams params_;
  shm::Geometry geometry_;
  shm::Mapped map_;
  bool linked_ = false;
  uint64_t device_ = 0, inode_ = 0;  // identity of our object, so Unlink never removes another's
};

}  // namespace sim4cv::transport
