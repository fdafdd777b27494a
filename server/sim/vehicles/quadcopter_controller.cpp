#include "server/sim/vehicles/quadcopter_controller.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim4cv::vehicles {
namespace {

constexpr double kGravity = 9.81;

Eigen::Vector2d ClampNorm(const Eigen::Vector2d& v, double limit) {
  const double norm = v.norm();
  return norm > limit ? Eigen::Vector2d(v * (limit / norm)) : v;
}

Eigen::Vector2d Rotate(const Eigen::Vector2d& v, double angle) { return Eigen::Rotation2Dd(angle) * v; }

double WrapAngle(double radians) { return std::remainder(radians, 2.0 * std::numbers::pi); }

}  // namespace

QuadcopterController::QuadcopterController(const QuadcopterGains& gains, const QuadcopterModel& model)
    : gains_(gains),
      model_(model),
      altitude_pid_(gains.altitude),
      velocity_x_pid_(gains.velocity),
      velocity_y_pid_(gains.velocity) {}

void QuadcopterController::Reset(const VehicleState& state) {
  altitude_pid_.Reset();
  velocity_x_pid_.Reset();
  velocity_y_pid_.Reset();
  altitude_reference_ = state.position.z();
  tilt_saturated_ = false;
}

double QuadcopterController::Thrust(const QuadcopterCommand& command, const VehicleState& state, double dt) {
  const double climb_rate = command.velocity.z();
  if (command.mode == QuadcopterCommand::Mode::kPosition) {
    altitude_reference_ = command.position.z();
  } else {
    altitude_reference_ += climb_rate * dt;
  }
  // Keep the reference within reach: a far target gives a bounded climb, and
  // a climb the UAV cannot follow does not wind the reference up.
  const double z = state.position.z();
  altitude_reference_ = std::clamp(altitude_reference_, z - gains_.max_altitude_error, z + gains_.max_altitude_error);
  const double vertical_accel =
      command.acceleration.z() +
      altitude_pid_.Update(altitude_reference_ - z, climb_rate - state.linear_velocity.z(), dt);
  // Gravity feed-forward, and only the vertical share of a tilted thrust
  // holds the UAV up.
  const double cos_tilt = std::max((state.orientation * Eigen::Vector3d::UnitZ()).z(), 0.5);
  return std::clamp(model_.mass * (kGravity + vertical_accel) / cos_tilt, 0.0, model_.max_thrust);
}

Eigen::Vector2d QuadcopterController::HorizontalAcceleration(const QuadcopterCommand& command,
                                                             const VehicleState& state, double yaw, double dt) {
  Eigen::Vector2d velocity_reference = command.velocity.head<2>();
  Eigen::Vector2d accel_reference = command.acceleration.head<2>();
  if (command.frame == QuadcopterCommand::Frame::kHeading) {
    velocity_reference = Rotate(velocity_reference, yaw);
    accel_reference = Rotate(accel_reference, yaw);
  }
  if (command.mode == QuadcopterCommand::Mode::kPosition) {
    velocity_reference +=
        ClampNorm(gains_.position_kp * (command.position - state.position).head<2>(), gains_.max_horizontal_speed);
  }
  // The loops run on world axes, so their integrators hold a world-fixed
  // bias (wind) while the UAV turns; the result is rotated into the
  // yaw-aligned frame where it becomes roll and pitch. The known drag at the
  // set velocity is fed forward (as gravity is for the thrust), and so is the
  // commanded acceleration.
  const Eigen::Vector2d error = velocity_reference - state.linear_velocity.head<2>();
  const Eigen::Vector2d accel_world = accel_reference + model_.drag * velocity_reference +
                                      Eigen::Vector2d(velocity_x_pid_.Update(error.x(), 0.0, dt, !tilt_saturated_),
                                                      velocity_y_pid_.Update(error.y(), 0.0, dt, !tilt_saturated_));
  const Eigen::Vector2d accel_heading = Rotate(accel_world, -yaw);
  const double limit = kGravity * std::tan(gains_.max_tilt_deg * std::numbers::pi / 180.0);
  tilt_saturated_ = accel_heading.norm() > limit;
  return ClampNorm(accel_heading, limit);
}

QuadcopterActuation QuadcopterController::Update(const QuadcopterCommand& command, const VehicleState& state,
                                                 double dt) {
  const double yaw = Yaw(state.orientation);
  QuadcopterActuation out;
  out.thrust = Thrust(command, state, dt);

  // Desired attitude: the current heading, then pitch and roll (Euler
  // z-y-x, in the yaw-aligned frame) chosen so that the thrust axis points
  // along (a_x, a_y, g). Pitch about +y tips the nose down and accelerates
  // along +x; roll about +x tips the right side down and accelerates along
  // -y. The tilt is then exactly atan(|a| / g) <= max_tilt, and the heading
  // is unchanged.
  const Eigen::Vector2d accel = HorizontalAcceleration(command, state, yaw, dt);
  const double pitch = std::atan2(accel.x(), kGravity);
  const double roll = std::asin(-accel.y() / Eigen::Vector3d(accel.x(), accel.y(), kGravity).norm());
  out.desired_orientation = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());

  // Attitude error as a rotation vector in the body frame, the short way round.
  Eigen::Quaterniond error = state.orientation.conjugate() * out.desired_orientation;
  if (error.w() < 0) error.coeffs() *= -1.0;
  const Eigen::AngleAxisd error_axis_angle(error);
  const Eigen::Vector3d angle_error = error_axis_angle.angle() * error_axis_angle.axis();

  const double yaw_correction =
      command.mode == QuadcopterCommand::Mode::kPosition ? gains_.yaw_kp * WrapAngle(command.yaw - yaw) : 0.0;
  const double yaw_rate = std::clamp(command.yaw_rate + yaw_correction, -gains_.max_yaw_rate, gains_.max_yaw_rate);
  // The yaw rate is commanded about body z, which is world z up to the tilt.
  const Eigen::Vector3d rate_setpoint(gains_.attitude_kp * angle_error.x(), gains_.attitude_kp * angle_error.y(),
                                      yaw_rate);
  const Eigen::Vector3d body_rate = state.orientation.conjugate() * state.angular_velocity;
  const Eigen::Vector3d rate_error = rate_setpoint - body_rate;
  const Eigen::Vector3d angular_accel(gains_.rate_kp * rate_error.x(), gains_.rate_kp * rate_error.y(),
                                      gains_.yaw_rate_kp * rate_error.z());
  // Plus the gyroscopic term w x (J w), so that spinning about z does not
  // couple into roll and pitch.
  const Eigen::Vector3d gyroscopic = body_rate.cross(model_.inertia.cwiseProduct(body_rate));
  out.torque = (model_.inertia.cwiseProduct(angular_accel) + gyroscopic)
                   .cwiseMax(-model_.max_torque)
                   .cwiseMin(model_.max_torque);
  return out;
}

}  // namespace sim4cv::vehicles
