// Shared-memory adapter: a frame ring in a sealed memfd that clients map
// read-only (one writer, any number of lock-free readers, a seqlock per
// slot), plus one sealed area per client for its requests and responses,
// handed to clients over an abstract Unix socket. Layout:
// protocol/shm_layout.h; rules: docs/protocol.md section 13.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "protocol/shm_layout.h"
#include "server/transport/shm/shm_region.h"
#include "server/common/limits.h"
#include "server/transport/transport.h"

namespace sim4cv::transport {

struct ShmOptions {
  std::string name;                 // --shm-name, e.g. "/sim4cv": names the Unix socket clients attach through
  std::string camera = "uav";       // the camera whose frames the ring carries
  uint32_t slot_count = 8;          // frame slots in the ring
  uint32_t width = 0, height = 0;   // the camera's image size, which sizes the slots (required)
  uint32_t expiry_ms = 5000;        // a client that sends nothing this long is disconnected
  uint32_t max_clients = limits::kShmMaxClients;  // shared-memory clients attached at once
  // Bit (1 << proto::Channel) per pixel channel the slots carry (--shm-channels): a
  // ring without the channels its readers skip copies and holds less per frame.
  channels::ChannelSet channel_mask = kShmDefaultChannels;
};

// Creates the frame object and listens at once; serves after Start; closes
// the ring and ends every attachment on Stop. Throws std::runtime_error if the
// memory cannot be created or the name is taken, std::invalid_argument for
// bad options.
std::unique_ptr<Transport> MakeShmTransport(const ShmOptions& options);

}  // namespace sim4cv::transport
