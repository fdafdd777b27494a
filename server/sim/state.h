// The mutable half of the simulation (after MuJoCo's mjData): everything a
// step changes. Logging, replay and the determinism tests read this struct.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

namespace sim4cv::sim {

struct BodyState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body -> world
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();

  // Heading about the world z axis, radians (0 = east, counter-clockwise).
  double Yaw() const;
};

// What the car's actuators are told. Either the waypoint follower writes it
// each physics step, or a client's Controls set it (manual == true).
struct CarCommand {
  float steering = 0.0f;  // -1 (full left) .. +1 (full right)
  float throttle = 0.0f;  // 0 .. 1
  float brake = 0.0f;     // 0 .. 1
  bool manual = false;
};

// The latest box a client's tracker reported, as applied by the simulation.
struct TrackerReport {
  uint32_t client_id = 0;
  uint64_t frame_id = 0;
  float x = 0, y = 0, width = 0, height = 0;
  float confidence = 0;
};

struct State {
  uint64_t frame_id = 0;       // frames completed; frame N is rendered after N frame periods
  uint64_t physics_steps = 0;  // substeps taken since start
  double sim_time = 0.0;       // seconds
  BodyState car;
  BodyState uav;
  CarCommand car_command;
  std::vector<TrackerReport> tracker_reports;  // one per client that reported, ordered by client id
};

}  // namespace sim4cv::sim
