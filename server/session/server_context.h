// What every transport's sessions share: the immutable scene and settings,
// the queue into the sim thread, and the latest published state snapshot.
#pragma once

#include <cstdint>
#include <mutex>
#include <string>

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

// The world's entities and cameras as the sim thread last published them
// (at start and after every change), so network threads can answer Hello and
// validate Subscribe by camera name without touching the simulation.
class WorldDirectory {
 public:
  void Publish(proto::WorldInfo world) {
    std::lock_guard lock(mutex_);
    world_ = std::move(world);
  }
  proto::WorldInfo Get() const {
    std::lock_guard lock(mutex_);
    return world_;
  }
  bool HasCamera(const std::string& name) const {
    std::string ignored;
    return FindCamera(name, ignored) >= 0;
  }
  // Index of the camera called `name`, or -1 and the current names in `names`.
  int FindCamera(const std::string& name, std::string& names) const {
    std::lock_guard lock(mutex_);
    for (int i = 0; i < world_.cameras_size(); ++i) {
      const std::string& camera = world_.cameras(i).name();
      if (camera.empty()) continue;  // a removed camera keeps its index, nameless
      if (camera == name) return i;
      names += (names.empty() ? "'" : ", '") + camera + "'";
    }
    return -1;
  }

 private:
  mutable std::mutex mutex_;
  proto::WorldInfo world_;
};

struct ServerContext {
  // The scene the daemon started with: its cameras' sizes fix the shm ring's.
  // Anything that can change since (entities, cameras, the map) is in `world`.
  const sim::Scene& scene;
  proto::SimMode mode;
  proto::Welcome welcome;  // complete but for client_id and what `world` holds; fixed once transports listen
  WorldDirectory& world;
  CommandQueue& commands;
  LatestState& latest_state;
  uint32_t max_message_bytes;
  Counters& counters;
  // What Hello.token must be (docs/security.md); empty with --no-auth.
  std::string access_token;
  // Where the daemon wrote it, for the refusal's message (the file is
  // readable only by the daemon's user).
  std::string access_token_file;
};

}  // namespace sim4cv::session
