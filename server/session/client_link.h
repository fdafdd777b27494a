// What the sim thread may do to a connected client: hand it a frame. Each
// transport's session implements this; the call never blocks and never does
// I/O on the sim thread (after LibCarla's streaming sessions).
#pragma once

#include <cstdint>

#include "server/session/frame.h"

namespace sim4cv::session {

class ClientLink {
 public:
  virtual ~ClientLink() = default;
  // Offers `frame` for delivery. Newest-frame subscribers keep only the latest
  // undelivered frame and count the one it replaces as dropped.
  virtual void OfferFrame(const FrameRef& frame) = 0;
};

}  // namespace sim4cv::session
