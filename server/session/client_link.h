// What the sim thread may do to a connected client: hand it a frame, or
// answer it (a request only the sim thread can validate and apply). Each
// transport's session implements this; the calls never block on I/O and never
// do I/O on the sim thread (after LibCarla's streaming sessions).
#pragma once

#include <cstdint>

#include "server/session/frame.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

class ClientLink {
 public:
  virtual ~ClientLink() = default;
  // Offers `frame` for delivery. Newest-frame subscribers keep only the latest
  // undelivered frame and count the one it replaces as dropped.
  virtual void OfferFrame(const FrameRef& frame) = 0;

  // Sim thread: answers the client. The transport sends `reply` the way it
  // sends ClientProtocol's replies, and before any frame offered after this
  // call; after a fatal Error it closes the client, as for ClientProtocol's.
  // A client that is already gone drops it. May allocate (configuration is
  // rare); the frame path must not.
  virtual void OfferReply(proto::Envelope reply) = 0;

  // Sim thread, before it renders a frame of `camera_index` at width x
  // height: a subscriber that can take pixels straight from the renderer
  // (the shared-memory ring) points `targets` at where the channels it
  // carries go and returns true; the next frame it is offered publishes them
  // without copying. Others keep this default.
  virtual bool PrepareTargets(uint32_t /*camera_index*/, uint32_t /*width*/, uint32_t /*height*/,
                              PixelTargets& /*targets*/) {
    return false;
  }
  // Whether this subscriber sends the Frame's own pixels: false for one whose
  // frames travel another way (a shared-memory client reads the ring), so
  // no pixels are copied into the Frame for it.
  virtual bool SendsFramePixels() const { return true; }
};

}  // namespace sim4cv::session
