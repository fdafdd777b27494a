// Unit tests of the pure controllers (server/sim/controllers.*).
#include "server/sim/controllers.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/support/no_warnings.h"

namespace sim4cv::sim {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;

UavSetpoint FollowCar(const UavSpec& uav, double pitch_down_deg, const BodyState& car) {
  UavOrder order;
  order.altitude = uav.altitude;
  order.pitch_down_deg = pitch_down_deg;
  return FollowTarget(order, car);
}

BodyState Car(double x, double y, double yaw, double speed) {
  BodyState body;
  body.position = {x, y, 0.75};
  body.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ()));
  body.linear_velocity = {speed * std::cos(yaw), speed * std::sin(yaw), 0};
  return body;
}

TEST(ControllersTest, YawOfABody) {
  EXPECT_NEAR(Car(0, 0, 0.3, 0).Yaw(), 0.3, 1e-12);
  EXPECT_NEAR(Car(0, 0, -2.0, 0).Yaw(), -2.0, 1e-12);
}

TEST(ControllersTest, FollowCarHoldsStationBehindAndAbove) {
  UavSpec uav;
  uav.altitude = 15.0;
  const double pitch_deg = 60.0;
  const double yaw = 30 * kPi / 180;
  BodyState car = Car(10, 20, yaw, 5);
  car.angular_velocity = {0, 0, 0.25};
  const UavSetpoint setpoint = FollowCar(uav, pitch_deg, car);
  const double behind = 15.0 / std::tan(pitch_deg * kPi / 180);
  EXPECT_NEAR(behind, 8.660254, 1e-6);
  EXPECT_NEAR(setpoint.position.x(), 10 - std::cos(yaw) * behind, 1e-9);
  EXPECT_NEAR(setpoint.position.y(), 20 - std::sin(yaw) * behind, 1e-9);
  EXPECT_NEAR(setpoint.position.z(), 0.75 + 15.0, 1e-9);
  // Horizontal distance behind the car.
  EXPECT_NEAR((setpoint.position - car.position).head<2>().norm(), behind, 1e-9);
  EXPECT_NEAR(setpoint.yaw, yaw, 1e-12);
  EXPECT_NEAR(setpoint.yaw_rate, 0.25, 1e-12);
  // The car's velocity plus the turning offset's: yaw_rate z x (setpoint - car).
  const Vector3d offset = setpoint.position - car.position;
  const Vector3d expected_velocity = car.linear_velocity + car.angular_velocity.cross(offset);
  EXPECT_NEAR((setpoint.velocity - expected_velocity).norm(), 0.0, 1e-9)
      << setpoint.velocity.transpose() << " vs " << expected_velocity.transpose();
}

TEST(ControllersTest, FollowCarOnAStraightMovesWithTheCar) {
  const UavSpec uav;
  const BodyState car = Car(1, 2, -0.4, 6);
  EXPECT_EQ(FollowCar(uav, 60.0, car).velocity, car.linear_velocity);
}

// Regression (fixed in 0c89881): FollowCar used to set setpoint.velocity =
// car.linear_velocity, but the setpoint (a point `behind` metres behind a
// yawing car) moves at car velocity + yaw_rate x offset; for a car turning at
// 0.3 rad/s the feed-forward was off by 0.3 * 8.66 = 2.6 m/s sideways, and the
// UAV lagged ~2 m behind its station in every bend (see world_test).
TEST(ControllersTest, FollowCarVelocityIsTheSetpointsRateOfChange) {
  const UavSpec uav;
  const double dt = 1e-6;
  BodyState car = Car(5, -3, 0.7, 6);
  car.angular_velocity = {0, 0, 0.3};
  BodyState later = car;
  later.position += car.linear_velocity * dt;
  later.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7 + 0.3 * dt, Vector3d::UnitZ()));
  const UavSetpoint now = FollowCar(uav, 60.0, car);
  const UavSetpoint next = FollowCar(uav, 60.0, later);
  const Vector3d rate = (next.position - now.position) / dt;
  EXPECT_NEAR((now.velocity - rate).norm(), 0.0, 1e-3)
      << "setpoint velocity " << now.velocity.transpose() << ", setpoint moves at " << rate.transpose();
  EXPECT_NEAR(next.yaw - now.yaw, 0.3 * dt, 1e-9);
}

TEST(ControllersTest, FollowCarStraightDownIsDirectlyAbove) {
  UavSpec uav;
  uav.altitude = 12.0;
  const BodyState car = Car(-3, 4, 1.0, 0);
  const UavSetpoint setpoint = FollowCar(uav, 90.0, car);
  EXPECT_NEAR(setpoint.position.x(), -3, 1e-9);
  EXPECT_NEAR(setpoint.position.y(), 4, 1e-9);
  EXPECT_NEAR(setpoint.position.z(), 12.75, 1e-9);
}

TEST(ControllersTest, WrapAngle) {
  EXPECT_NEAR(WrapAngle(0.0), 0.0, 1e-12);
  EXPECT_NEAR(WrapAngle(0.5), 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(-0.5), -0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(2 * kPi + 0.5), 0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(-2 * kPi - 0.5), -0.5, 1e-12);
  EXPECT_NEAR(WrapAngle(7.0), 7.0 - 2 * kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-7.0), -7.0 + 2 * kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(100 * kPi + 1.0), 1.0, 1e-9);
  // The half-open interval (-pi, pi]: both ends map to +pi.
  EXPECT_DOUBLE_EQ(WrapAngle(kPi), kPi);
  EXPECT_DOUBLE_EQ(WrapAngle(-kPi), kPi);
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-9);
  for (double a = -20; a <= 20; a += 0.37) {
    const double w = WrapAngle(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::remainder(w - a, 2 * kPi), 0.0, 1e-9);
  }
}

}  // namespace
}  // namespace sim4cv::sim
