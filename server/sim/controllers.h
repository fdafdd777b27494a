// Controllers that turn the state into actuator commands. Pure functions of
// (spec, state) so they are deterministic and unit-testable.
#pragma once

#include <Eigen/Core>

#include "server/sim/scene.h"
#include "server/sim/state.h"
#include "server/sim/vehicles/quadcopter_controller.h"

namespace sim4cv::sim {

// Where a filming UAV wants to be: behind its target and `altitude` above
// it, so that a camera pitched down `pitch_down_deg` looks straight at it.
struct UavSetpoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double yaw = 0.0;
  double yaw_rate = 0.0;
};
UavSetpoint FollowTarget(const UavOrder& order, const BodyState& target);

// The quadcopter command that carries out `order` in `state`. A follow order
// whose target is gone holds the UAV where it is.
vehicles::QuadcopterCommand UavCommandFor(const UavOrder& order, const BodyState& uav, const State& state);

// Wraps an angle to (-pi, pi].
double WrapAngle(double radians);

}  // namespace sim4cv::sim
