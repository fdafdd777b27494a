// Pose and velocity of a vehicle as plain Eigen values, in the conventions of
// the simulation State (server/sim/state.h): world z up; body x forward, y
// left, z up. Kept free of Bullet so the lead can copy it field by field.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace sim4cv::vehicles {

struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body -> world
};

struct VehicleState {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body -> world
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();        // world frame, m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();       // world frame, rad/s

  Pose pose() const { return {position, orientation}; }
};

// Heading of the body x axis about world z (0 = +x, counter-clockwise), rad.
// Undefined only when x points straight up or down, which neither vehicle reaches.
inline double Yaw(const Eigen::Quaterniond& orientation) {
  const Eigen::Vector3d forward = orientation * Eigen::Vector3d::UnitX();
  return std::atan2(forward.y(), forward.x());
}

// Angle between the body z axis and world z, rad.
inline double Tilt(const Eigen::Quaterniond& orientation) {
  const double cos_tilt = (orientation * Eigen::Vector3d::UnitZ()).z();
  return std::acos(std::clamp(cos_tilt, -1.0, 1.0));
}

}  // namespace sim4cv::vehicles
