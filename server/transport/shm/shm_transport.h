// Shared-memory adapter: a POSIX shared-memory frame ring (one writer, any
// number of lock-free readers, seqlock per slot) plus a reply ring from
// clients to the daemon. Layout: protocol/shm_layout.h.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "protocol/shm_layout.h"
#include "server/transport/transport.h"

namespace sim4cv::transport {

struct ShmOptions {
  std::string name;                 // POSIX shm object name, e.g. "/sim4cv"
  std::string camera = "uav";       // the camera whose frames the ring carries
  uint32_t slot_count = 8;          // frame slots in the ring
  uint32_t reply_slot_count = 256;  // messages the reply ring holds before dropping the oldest
  uint32_t width = 0, height = 0;   // the camera's image size, which sizes the slots (required)
  uint32_t expiry_ms = 5000;        // a client that sends nothing this long is disconnected
  uint32_t max_clients = 64;        // response-area entries: shared-memory clients at once
  uint32_t reply_spin_us = 0;       // how long the reply thread polls before it sleeps in FUTEX_WAIT
  // Bit (1 << proto::Channel) per pixel channel the slots carry (--shm-channels): a
  // ring without the channels its readers skip copies and holds less per frame.
  uint32_t channel_mask = shm::kShmAllPixelChannels;
};

// Creates (replacing a stale one) and maps the object at once; serves after
// Start; removes it on Stop. Throws std::runtime_error naming the object if it
// cannot be created, std::invalid_argument for bad options.
std::unique_ptr<Transport> MakeShmTransport(const ShmOptions& options);

}  // namespace sim4cv::transport
