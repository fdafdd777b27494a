#include "server/sim/controllers.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim4cv::sim {

double BodyState::Yaw() const {
  const Eigen::Vector3d forward = orientation * Eigen::Vector3d::UnitX();
  return std::atan2(forward.y(), forward.x());
}

double WrapAngle(double radians) {
  const double wrapped = std::remainder(radians, 2.0 * std::numbers::pi);
  return wrapped <= -std::numbers::pi ? wrapped + 2.0 * std::numbers::pi : wrapped;
}

UavSetpoint FollowCar(const UavSpec& uav, double pitch_down_deg, const BodyState& car) {
  const double yaw = car.Yaw();
  const double behind = uav.altitude / std::tan(pitch_down_deg * std::numbers::pi / 180.0);
  UavSetpoint setpoint;
  setpoint.position = car.position + Eigen::Vector3d(-std::cos(yaw) * behind, -std::sin(yaw) * behind, uav.altitude);
  // The offset behind the car turns with it, so its rate of change joins the car's velocity.
  const double yaw_rate = car.angular_velocity.z();
  setpoint.velocity = car.linear_velocity + Eigen::Vector3d(std::sin(yaw), -std::cos(yaw), 0.0) * behind * yaw_rate;
  setpoint.yaw = yaw;
  setpoint.yaw_rate = yaw_rate;
  return setpoint;
}

}  // namespace sim4cv::sim
