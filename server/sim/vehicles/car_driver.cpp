#include "server/sim/vehicles/car_driver.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim4cv::vehicles {

CarDriver::CarDriver(const CarParams& car, Polyline path, double set_speed, const CarDriverParams& params)
    : car_(car), path_(std::move(path)), set_speed_(set_speed), params_(params), speed_pid_(params.speed) {}

Polyline::Projection CarDriver::Track(const Eigen::Vector2d& rear_axle) {
  Polyline::Projection projection;
  if (progress_ >= 0) projection = path_.ProjectNear(rear_axle, progress_, params_.search_window);
  if (progress_ < 0 || projection.distance > params_.relocate_distance) projection = path_.Project(rear_axle);
  progress_ = projection.arc_length;
  return projection;
}

double CarDriver::Steering(const Eigen::Vector2d& rear_axle, double arc_length, double yaw, double speed) const {
  const double lookahead = std::clamp(params_.lookahead_min + params_.lookahead_time * std::abs(speed),
                                      params_.lookahead_min, params_.lookahead_max);
  const Eigen::Vector2d target = path_.PointAt(arc_length + lookahead);
  // Target in the car's frame (x forward, y left). The arc from the rear axle,
  // tangent to the heading, through the target has curvature 2 y / d^2; a
  // bicycle model turns that into a wheel angle.
  const Eigen::Vector2d delta = target - rear_axle;
  const double local_x = std::cos(yaw) * delta.x() + std::sin(yaw) * delta.y();
  const double local_y = -std::sin(yaw) * delta.x() + std::cos(yaw) * delta.y();
  const double curvature = 2.0 * local_y / std::max(local_x * local_x + local_y * local_y, 1e-6);
  const double wheel_angle_left = std::atan(curvature * car_.wheelbase);
  const double max_angle = car_.max_steering_deg * std::numbers::pi / 180.0;
  return std::clamp(-wheel_angle_left / max_angle, -1.0, 1.0);  // positive steering is to the right
}

double CarDriver::TargetSpeed(double arc_length) const {
  if (path_.closed()) return set_speed_;
  // From the box centre, half a wheelbase ahead of the rear axle.
  const double remaining = path_.length() - arc_length - car_.wheelbase / 2.0 - params_.stop_distance;
  if (remaining <= 0.0) return 0.0;
  return std::min(set_speed_, std::sqrt(2.0 * params_.stop_deceleration * remaining));
}

CarControls CarDriver::Update(const VehicleState& car, double dt) {
  const Eigen::Vector3d forward = car.orientation * Eigen::Vector3d::UnitX();
  const double speed = car.linear_velocity.dot(forward);
  const double yaw = std::atan2(forward.y(), forward.x());
  const Eigen::Vector2d rear_axle = car.position.head<2>() - forward.head<2>().normalized() * (car_.wheelbase / 2.0);

  CarControls controls;
  const double arc_length = Track(rear_axle).arc_length;
  controls.steering = Steering(rear_axle, arc_length, yaw, speed);
  const double target = TargetSpeed(arc_length);
  if (target == 0.0) {
    controls.brake = 1.0;
    speed_pid_.Reset();
    return controls;
  }
  // Feed-forward: the force that balances the car's drag at the target speed.
  const double feed_forward =
      (car_.drag_linear * target + car_.drag_quadratic * target * target) / car_.max_engine_force;
  const double error = target - speed;
  const bool integrate = !(saturated_high_ && error > 0) && !(saturated_low_ && error < 0);
  const double u = feed_forward + speed_pid_.Update(error, 0.0, dt, integrate);
  // Braking force in the same units as the engine's, so u maps to one
  // continuous longitudinal force.
  const double brake_scale = car_.max_engine_force / car_.max_brake_force;
  saturated_high_ = u > 1.0;
  saturated_low_ = -u * brake_scale > 1.0;
  controls.throttle = std::clamp(u, 0.0, 1.0);
  controls.brake = std::clamp(-u * brake_scale, 0.0, 1.0);
  return controls;
}

}  // namespace sim4cv::vehicles
