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

CarCommand FollowLane(const CarSpec& car, const ClosedPath& lane, const BodyState& body) {
  const Eigen::Vector2d position = body.position.head<2>();
  const double yaw = body.Yaw();
  const auto projection = lane.Project(position);
  const Eigen::Vector2d target = lane.PointAt(projection.arc_length + car.lookahead);

  // Target in the car's frame (x forward, y left); pure pursuit curvature
  // 2*y/d^2 turns into a bicycle-model steering angle.
  const Eigen::Vector2d delta = target - position;
  const double local_x = std::cos(yaw) * delta.x() + std::sin(yaw) * delta.y();
  const double local_y = -std::sin(yaw) * delta.x() + std::cos(yaw) * delta.y();
  const double distance_sq = std::max(local_x * local_x + local_y * local_y, 1e-6);
  const double curvature = 2.0 * local_y / distance_sq;
  const double steer_angle = std::atan(curvature * car.wheelbase);
  const double max_steer = car.max_steer_deg * std::numbers::pi / 180.0;

  CarCommand command;
  // Positive steering turns right, i.e. towards negative curvature.
  command.steering = static_cast<float>(std::clamp(-steer_angle / max_steer, -1.0, 1.0));
  const double forward_speed = body.linear_velocity.head<2>().dot(Eigen::Vector2d(std::cos(yaw), std::sin(yaw)));
  const double wanted_accel = 1.5 * (car.cruise_speed - forward_speed);
  command.throttle = static_cast<float>(std::clamp(wanted_accel / car.max_accel, 0.0, 1.0));
  command.brake = static_cast<float>(std::clamp(-wanted_accel / car.max_brake_decel, 0.0, 1.0));
  return command;
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
