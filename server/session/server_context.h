// What every transport's sessions share: the immutable scene and settings,
// the queue into the sim thread, and the latest published state snapshot.
#pragma once

#include <cstdint>
#include <mutex>

#include "server/session/command_queue.h"
#include "server/session/counters.h"
#include "server/session/frame.h"
#include "server/sim/scene.h"
#include "sim4cv.pb.h"

namespace sim4cv::session {

// The newest StateSnapshot, swapped in by the sim thread once per frame.
class LatestState {
 public:
  void Publish(StateRef snapshot) {
    std::lock_guard lock(mutex_);
    latest_ = std::move(snapshot);
  }
  StateRef Get() const {
    std::lock_guard lock(mutex_);
    return latest_;
  }

 private:
  mutable std::mutex mutex_;
  StateRef latest_;
};

struct ServerContext {
  const sim::Scene& scene;
  proto::SimMode mode;
  proto::Welcome welcome;  // complete but for client_id; fixed once transports listen
  CommandQueue& commands;
  LatestState& latest_state;
  uint32_t max_message_bytes;
  Counters& counters;
};

}  // namespace sim4cv::session
