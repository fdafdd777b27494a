// Controllers that turn the state into actuator commands. Pure functions of
// (spec, state) so they are deterministic and unit-testable.
#pragma once

#include <Eigen/Core>

#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::sim {

// Where the camera UAV wants to be: behind the car and `altitude` above it, so
// that a camera pitched down `pitch_down_deg` looks straight at the car.
struct UavSetpoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double yaw_rate = 0.0;
};
UavSetpoint FollowCar(const UavSpec& uav, double pitch_down_deg, const BodyState& car);

// Wraps an angle to (-pi, pi].
double WrapAngle(double radians);

}  // namespace sim4cv::sim
