// Recording a car's motion per physics step and replaying it exactly: the
// target of the tracking benchmark drives the same path for every tracker
// (Sim4CV replays the car "from a log file to ensure equal conditions").
// File format: docs/vehicles.md#trajectory-files.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include "server/sim/vehicles/bullet_body.h"
#include "server/sim/vehicles/car.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

struct TrajectorySample {
  uint64_t step = 0;     // physics steps since the recording began; sample 0 is the start
  VehicleState state;    // the car's State() after that step
  CarControls controls;  // the controls it was driven with during that step
};

struct Trajectory {
  double dt = 0.0;  // seconds per physics step
  std::vector<TrajectorySample> samples;
};

// Version-1 binary format, little-endian. Read* throws std::invalid_argument
// naming what is wrong (bad magic, unknown version, truncated data).
void WriteTrajectory(const Trajectory& trajectory, std::ostream& out);
Trajectory ReadTrajectory(std::istream& in);
void SaveTrajectory(const Trajectory& trajectory, const std::string& path);
Trajectory LoadTrajectory(const std::string& path);

// Call Record once before the first physics step (sample 0) and once after
// every step.
class TrajectoryRecorder {
 public:
  explicit TrajectoryRecorder(double dt);
  void Record(const VehicleState& state, const CarControls& controls);
  void Record(const Car& car) { Record(car.State(), car.controls()); }
  const Trajectory& trajectory() const { return trajectory_; }

 private:
  Trajectory trajectory_;
};

// Moves a kinematic box along a recording: the box is placed exactly at each
// sample's pose (Bullet derives its velocity for contacts), and State()
// returns the recorded values bit for bit, whatever Bullet's float
// transform rounds them to.
class TrajectoryPlayer {
 public:
  // Adds a kinematic box of `half_extents` (centred on the recorded
  // position) at sample 0. The trajectory must not be empty.
  TrajectoryPlayer(btDiscreteDynamicsWorld& world, Trajectory trajectory, const Eigen::Vector3d& half_extents);

  // Moves to the next sample. Call once before every stepSimulation(dt, 0),
  // so that after step k the body is at sample k. Returns false, staying on
  // the last sample, once the recording is over.
  bool Advance();

  const TrajectorySample& current() const { return trajectory_.samples[index_]; }
  const VehicleState& State() const { return current().state; }
  std::size_t index() const { return index_; }
  bool finished() const { return index_ + 1 >= trajectory_.samples.size(); }
  const Trajectory& trajectory() const { return trajectory_; }
  btRigidBody& body() { return body_.body(); }

 private:
  static const Trajectory& CheckNotEmpty(const Trajectory& trajectory);
  void PlaceBody();

  Trajectory trajectory_;
  std::size_t index_ = 0;
  btBoxShape box_;
  BodyInWorld body_;
};

}  // namespace sim4cv::vehicles
