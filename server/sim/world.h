// The Bullet world: the only code that touches Bullet. It reads actuator
// commands from State, applies forces, takes one fixed physics step and
// writes the bodies' poses and velocities back into State.
#pragma once

#include <memory>

#include "server/sim/closed_path.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

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

  // Advances `state` by one physics step of `dt` seconds. Deterministic: the
  // same state and commands give the same result.
  void Step(State& state, double dt);

  // The lane the car's waypoint follower drives (right lane of the road loop).
  const ClosedPath& car_lane() const { return car_lane_; }

 private:
  struct Bullet;
  void ApplyCarForces(const State& state, double dt);
  void ApplyUavForces(const State& state);

  const Scene& scene_;
  ClosedPath car_lane_;
  std::unique_ptr<Bullet> bullet_;
};

}  // namespace sim4cv::sim
