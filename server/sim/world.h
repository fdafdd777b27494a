// The Bullet world: the only code that touches Bullet. Per physics step it
// turns each entity's command in State into its vehicle's actuator inputs,
// steps the world once, and writes the bodies' poses and velocities back
// into State.
//
// Unlike a pure mjData, the vehicles keep some step-to-step state of their own
// (the wheels' steering angle, the controllers' integrators, Bullet's contact
// cache); State holds everything observable. Two Worlds built from the same
// Scene, configured and stepped the same way, produce bit-identical States.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "server/sim/vehicles/polyline.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"
#include "server/sim/vehicles/polyline.h"

namespace sim4cv::runlog {
class ReplayTrack;
}

namespace sim4cv::sim {

// Where to place a new entity: on the ground (cars) or in the air (UAVs).
struct SpawnPose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // m; cars ignore z (they stand on the ground)
  double yaw = 0.0;                                    // rad, counter-clockwise from east
};

class World {
 public:
  // `scene` must outlive the World.
  explicit World(const Scene& scene);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  // The state at time zero: the scene's car at the start of its lane, its
  // camera UAV on station behind it.
  State InitialState() const;

  // Advances `state` by one physics step of `dt` seconds. Deterministic.
  void Step(State& state, double dt);

  // Configuration, between steps (the sim thread). Each throws
  // std::invalid_argument naming the offending value and changes nothing then.
  //
  // A new car at rest, its brake on until it gets Controls or a route; a new
  // UAV hovering; a new pedestrian standing (kinematic: no Bullet body)
  // until SetRoute gives it a path to walk. `name` must be unique (empty:
  // "car_<id>" / "uav_<id>" / "pedestrian_<id>").
  // Returns the new entity's id: the lowest free one.
  uint32_t Spawn(State& state, EntityKind kind, const std::string& name, const SpawnPose& pose);
  // Removes an entity; UAVs that followed it hold their position instead.
  void Remove(State& state, uint32_t id);
  // The car's waypoint follower drives `path` (a closed loop or an open
  // path, where it stops at the end) at `speed` m/s; speed 0 stops it there.
  // A pedestrian is put at the path's start and walks it at `speed` (at
  // most 10 m/s), looping if closed, else standing at its end.
  void SetRoute(State& state, uint32_t id, std::vector<Eigen::Vector2d> path, bool closed, float speed);
  // Only the set speed of a car or pedestrian that already has a route.
  void SetCruiseSpeed(State& state, uint32_t id, float speed);
  // What a UAV's controller holds from now on.
  void SetUavOrder(State& state, uint32_t id, const UavOrder& order);

  // Replay (docs/logs.md): from now on Step copies into State each replayed
  // entity's logged pose and velocity of the frame being stepped to
  // (state.frame_id + 1). A frame the log does not hold (past its end, or a
  // gap) keeps the previous pose at rest. `only` empty: every entity is
  // replayed and Bullet is not stepped at all (nothing else in the world
  // moves, and rendering reads State). Otherwise only the listed entities
  // are, and the rest is simulated around them: e.g. the tracking target
  // drives exactly its recorded path while the UAVs fly by physics. A
  // replayed car's chassis is put at its logged pose every step, so the
  // simulated bodies meet it where it is drawn.
  void SetReplay(std::shared_ptr<const runlog::ReplayTrack> track, std::vector<uint32_t> only = {});

  // The lane the scene's target car drives (right lane of its road loop).
  const vehicles::Polyline& car_lane() const { return car_lane_; }

 private:
  struct Bodies;
  struct Vehicle;

  Vehicle& VehicleOf(const State& state, uint32_t id, EntityKind kind, const char* what);
  void StepPhysics(State& state, double dt);
  void StepWalker(const Vehicle& vehicle, Entity& walker, double dt);
  void SetWalk(State& state, uint32_t id, std::vector<Eigen::Vector2d> path, bool closed, float speed);
  void StepTraffic(State& state, double dt);
  // Whether a car's follower must look out for others (traffic, other
  // simulated cars, spawned pedestrians): the look-ahead costs a path search.
  bool AnythingToGiveWayTo(const State& state) const;
  // Slows a car's waypoint follower for traffic, other simulated cars and
  // pedestrians standing or moving ahead on its path, so it neither drives
  // through a car nor runs down a walker.
  double SpeedForTraffic(const State& state, const Entity& car, const vehicles::Polyline& path) const;
  void FollowReplay(State& state) const;
  // Whether entity `id` follows the log (only while a replay is set).
  bool Replayed(uint32_t id) const;

  const Scene& scene_;
  vehicles::Polyline car_lane_;
  std::unique_ptr<Bodies> bodies_;
  State initial_state_;  // taken when the scene's bodies were spawned
  std::shared_ptr<const runlog::ReplayTrack> replay_;
  std::vector<uint32_t> replay_only_;         // sorted; empty: all
  std::vector<traffic::Obstacle> obstacles_;  // the entities' cars, for traffic: reused every step
  traffic::TrafficIds traffic_ids_;           // what the traffic's entities are called in logs
};

// The ids of a State's entities, as "1 ('car'), 2 ('uav')": for Error messages.
std::string EntityList(const State& state);

}  // namespace sim4cv::sim
