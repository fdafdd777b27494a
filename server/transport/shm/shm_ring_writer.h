// The frame ring's single writer: a ClientLink subscribed (newest-frame) to
// the ring's camera, so the sim thread hands it every frame it renders. The
// pixel channels the ring carries (--shm-channels) are rendered straight into
// the next slot (PrepareTargets) under that slot's seqlock, or copied there
// from a frame rendered elsewhere (Write without PrepareTargets, tests); the
// writer never waits for readers and overwrites the oldest slot.
#pragma once

#include <memory>

#include "server/session/client_link.h"
#include "server/transport/shm/shm_region.h"

namespace sim4cv::transport {

class ShmRingWriter : public session::ClientLink {
 public:
  ShmRingWriter(std::shared_ptr<ShmRegion> region, uint32_t camera_index);

  // Sim thread. Frames of other cameras are ignored. Never blocks, never allocates.
  void OfferFrame(const session::FrameRef& frame) override;
  // The same for a Frame not from a pool (tests).
  void Write(const session::Frame& frame);
  // Sim thread: opens the next slot for writing (its seqlock odd) and points
  // `targets` at its planes, if the frame is of the ring's camera and size.
  // The next Write/OfferFrame publishes that slot without copying pixels.
  bool PrepareTargets(uint32_t camera_index, uint32_t width, uint32_t height, session::PixelTargets& targets) override;
  // Nothing to do: the ring is a subscriber, not a client, so no request of
  // its own can be answered. Shared-memory clients are answered through
  // their own links (ShmClientLink).
  void OfferReply(proto::Envelope) override {}

  // Marks the ring closed and wakes every waiting reader (after the last frame).
  void Close();

 private:
  std::shared_ptr<ShmRegion> region_;  // keeps the mapping while the scheduler holds this link
  uint32_t camera_index_;
  uint64_t published_ = 0;
  bool prepared_ = false;  // the next slot holds the next frame's pixels already

  void OpenSlot(uint64_t publication);
};

}  // namespace sim4cv::transport
