// The mutable half of the simulation (after MuJoCo's mjData): everything a
// step changes. Logging, replay and the determinism tests read this struct.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "server/sim/entity_kinds.h"
#include "server/sim/traffic/traffic_state.h"

namespace sim4cv::sim {

struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body -> world
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();

  // Heading about the world z axis, radians (0 = east, counter-clockwise).
  double Yaw() const;
};

// What a car's actuators are told. Either its waypoint follower writes it
// each physics step, or a client's Controls set it (manual == true).
struct CarCommand {
  float steering = 0.0f;  // -1 (full left) .. +1 (full right)
  float throttle = 0.0f;  // 0 .. 1
  float brake = 0.0f;     // 0 .. 1
  bool manual = false;
  // Set by a client's Controls (and cleared when --controls-timeout-ms
  // braked the car): only then does the timeout watch the car, so a spawned
  // car parked with manual brakes is never "timed out". In State, not in the
  // sim thread, so that the timeout is measured in simulation time and a
  // lockstep run repeats exactly.
  bool from_controls = false;
  double controls_time = 0.0;  // State::sim_time when the last Controls were applied
};

// What a UAV's position-hold controller is asked to do.
struct UavOrder {
  enum class Mode : uint8_t {
    kFollow,    // film `target`: hold station behind and above it (the camera UAV of the paper)
    kHold,      // hold `position` with heading `yaw`
    kVelocity,  // fly `velocity` (world frame) turning at `yaw_rate`
    kTrack,     // steer by the newest box its cameras' trackers report (track_servo.h)
  };
  // kTrack: the servo's settings and memory, part of the state so that a
  // run repeats exactly.
  struct Track {
    // The camera the boxes are in (copied at the order: the servo needs no scene).
    double fov_y = 1.047;       // rad
    double pitch_down = 1.047;  // rad below the horizon (a gimbal holds it)
    double altitude = 15.0;     // m above the ground to hold
    double distance = 0.0;      // m behind the target to hold; 0: where the camera centre looks
    // Memory: the target's estimated position and velocity on the ground
    // (world frame), from the newest box used.
    uint64_t frame = 0;  // the report's frame_id; 0: none yet
    double time = 0.0;   // sim_time the report came
    Eigen::Vector2d target = Eigen::Vector2d::Zero();
    Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  };
  Mode mode = Mode::kFollow;
  uint32_t target = 0;                                 // kFollow: entity id
  double altitude = 15.0;                              // kFollow: m above the target
  double pitch_down_deg = 60.0;                        // kFollow: the gimbal pitch that frames the target
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // kHold, m
  double yaw = 0.0;                                    // kHold, rad
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // kVelocity, m/s
  double yaw_rate = 0.0;                               // kVelocity, rad/s
  Track track;                                         // kTrack
};

// One simulated vehicle or person: the scene's target car and camera UAV,
// and any a client spawned. Its id is also its instance id in masks and boxes.
// Pedestrians are kinematic: they walk their route at cruise_speed.
struct Entity {
  uint32_t id = 0;
  EntityKind kind = EntityKind::kCar;
  std::string name;
  BodyState body;
  CarCommand car_command;     // cars
  float cruise_speed = 0.0f;  // cars and pedestrians: the set speed along the route; 0 with no route
  double walked = 0.0;        // pedestrians: metres along their route
  UavOrder uav_order;         // UAVs
};

// The latest box a client's tracker reported, as applied by the simulation.
struct TrackerReport {
  uint32_t client_id = 0;
  uint64_t frame_id = 0;
  float x = 0, y = 0, width = 0, height = 0;
  float confidence = 0;
  // Where the box is: the entity the client's camera is mounted on (0: a
  // fixed camera) and the camera's size; when it came (State::sim_time).
  // Not logged: the servo's inputs, rebuilt by the reports of a new run.
  uint32_t entity_id = 0;
  uint32_t image_width = 0, image_height = 0;
  double received_at = 0.0;
};

struct State {
  uint64_t frame_id = 0;                       // frames completed; frame N is rendered after N frame periods
  uint64_t physics_steps = 0;                  // substeps taken since start
  double sim_time = 0.0;                       // seconds
  std::vector<Entity> entities;                // ordered by id
  traffic::TrafficState traffic;               // the map's moving cars and walkers (empty without traffic)
  std::vector<TrackerReport> tracker_reports;  // one per client that reported, ordered by client id

  // The entity with this id, or nullptr.
  const Entity* Find(uint32_t id) const;
  Entity* Find(uint32_t id);
  const Entity* FindByName(const std::string& name) const;
};

}  // namespace sim4cv::sim
