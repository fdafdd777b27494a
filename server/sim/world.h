// The Bullet world: the only code that touches Bullet. Per physics step it
// turns the State's commands into the vehicles' actuator inputs, steps the
// world once, and writes the bodies' poses and velocities back into State.
//
// Unlike a pure mjData, the vehicles keep some step-to-step state of their own
// (the wheels' steering angle, the controllers' integrators, Bullet's contact
// cache); State holds everything observable. Two Worlds built from the same
// Scene and stepped with the same commands produce bit-identical States.
#pragma once

#include <memory>

#include "server/sim/closed_path.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::runlog {
class ReplayTrack;
}

namespace sim4cv::sim {

class World {
 public:
  // `scene` must outlive the World.
  explicit World(const Scene& scene);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // The state at time zero: car at the start of its lane, UAV on station.
  State InitialState() const;

  // Advances `state` by one physics step of `dt` seconds. Deterministic.
  void Step(State& state, double dt);

  // Replay (docs/logs.md): from now on Step moves no body by physics; it
  // copies into State the car's and the UAV's logged poses and velocities of
  // the frame being stepped to (state.frame_id + 1). A frame the log does not
  // hold (past its end, or a gap) keeps the previous pose at rest. Bullet is
  // not stepped: nothing else in the world moves, and rendering reads State.
  void SetReplay(std::shared_ptr<const runlog::ReplayTrack> track);

  // The lane the car's waypoint follower drives (right lane of the road loop).
  const ClosedPath& car_lane() const { return car_lane_; }

 private:
  struct Bodies;

  void StepPhysics(State& state, double dt);
  void FollowReplay(State& state) const;

  const Scene& scene_;
  ClosedPath car_lane_;
  std::unique_ptr<Bodies> bodies_;
  State initial_state_;  // taken when the bodies were spawned
  std::shared_ptr<const runlog::ReplayTrack> replay_;
};

}  // namespace sim4cv::sim
