#include "server/sim/controllers.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim4cv::sim {

double WrapAngle(double radians) {
  const double wrapped = std::remainder(radians, 2.0 * std::numbers::pi);
  return wrapped <= -std::numbers::pi ? wrapped + 2.0 * std::numbers::pi : wrapped;
}

UavSetpoint FollowTarget(const UavOrder& order, const BodyState& car) {
  const double yaw = car.Yaw();
  const double behind = order.altitude / std::tan(order.pitch_down_deg * std::numbers::pi / 180.0);
  UavSetpoint setpoint;
  setpoint.position = car.position + Eigen::Vector3d(-std::cos(yaw) * behind, -std::sin(yaw) * behind, order.altitude);
  // The offset behind the car turns with it, so its rate of change joins the car's velocity.
  const double yaw_rate = car.angular_velocity.z();
  setpoint.velocity = car.linear_velocity + Eigen::Vector3d(std::sin(yaw), -std::cos(yaw), 0.0) * behind * yaw_rate;
  setpoint.yaw = yaw;
  setpoint.yaw_rate = yaw_rate;
  return setpoint;
}

vehicles::QuadcopterCommand UavCommandFor(const UavOrder& order, const BodyState& uav, const State& state) {
  using vehicles::QuadcopterCommand;
  switch (order.mode) {
    case UavOrder::Mode::kFollow:
      if (const Entity* target = state.Find(order.target)) {
        // The target's centripetal acceleration is fed forward so the UAV
        // does not lag in bends.
        const UavSetpoint station = FollowTarget(order, target->body);
        const Eigen::Vector3d turn_acceleration = target->body.angular_velocity.cross(target->body.linear_velocity);
        return QuadcopterCommand::Hold(station.position, station.yaw, station.velocity, station.yaw_rate,
                                       turn_acceleration);
      }
      return QuadcopterCommand::Hold(uav.position, uav.Yaw());
    case UavOrder::Mode::kHold:
      return QuadcopterCommand::Hold(order.position, order.yaw);
    case UavOrder::Mode::kVelocity:
      return QuadcopterCommand::Velocity(order.velocity, order.yaw_rate);
    case UavOrder::Mode::kTrack:  // World::Step asks TrackCommand (track_servo.h), which keeps memory
      break;
  }
  return QuadcopterCommand::Hold(uav.position, uav.Yaw());
}

}  // namespace sim4cv::sim
