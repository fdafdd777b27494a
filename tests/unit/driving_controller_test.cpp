// sim4cv::driving::Controller (clients/cpp/examples/driving/) against the
// hand-computed cases of docs/driving.md ("Controller") and values of
// clients/python/sim4cv/driving_control.py, which it mirrors.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "driving/controller.h"

namespace sim4cv::driving {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(DrivingController, TheDefaultsAreThoseOfDrivingControlPy) {
  const ControllerParams p = Controller().params();
  EXPECT_EQ(p.max_steering_deg, 35.0);
  EXPECT_EQ(p.gain, 1.0);
  EXPECT_EQ(p.t_max, 1.0);
  EXPECT_EQ(p.t_min, 0.3);
  EXPECT_EQ(p.k, 0.25);
}

TEST(DrivingController, AStraightGivesSteeringZeroAndFullThrottle) {
  const DriveControls c = Controller().FromWaypoints({2, 0, 4, 0, 6, 0, 8, 0});
  EXPECT_EQ(c.steering, 0.0);
  EXPECT_EQ(c.throttle, 1.0);
  EXPECT_EQ(c.brake, 0.0);
}

TEST(DrivingController, APointToTheRightSteersRightByTheAngleOverTheWheelLimit) {
  // atan(0.5 / 2) = 14.04 deg, over 35 deg: 0.401 (driving_control.py: 0.40103552765504225).
  const DriveControls c = Controller().FromWaypoints({2, 0.5f, 4, 0, 6, 0, 8, 0});
  EXPECT_NEAR(c.steering, 0.401, 5e-4);
  EXPECT_NEAR(c.steering, 0.40103552765504225, 1e-12);
  EXPECT_NEAR(Controller().Steering(2, -0.5), -0.40103552765504225, 1e-12);  // left is negative
  EXPECT_EQ(c.throttle, 1.0);
}

TEST(DrivingController, AnApproachingTurnLowersTheThrottleToItsFloor) {
  const Controller controller;
  // The radius-20 m right turn of docs/driving.md: h4 = 1.58 m.
  const DriveControls turn = controller.FromWaypoints({2.00f, 0.10f, 3.97f, 0.40f, 5.91f, 0.89f, 7.79f, 1.58f});
  EXPECT_NEAR(turn.throttle, 0.605, 1e-6);
  EXPECT_NEAR(turn.steering, 0.08178300646033565, 1e-7);  // Python's, from the same float inputs
  EXPECT_NEAR(controller.Throttle(1.58), 0.605, 1e-12);
  EXPECT_NEAR(controller.Throttle(-1.58), 0.605, 1e-12);  // |h4|: a left turn the same
  EXPECT_NEAR(controller.Throttle(2.8), 0.3, 1e-12);
  EXPECT_EQ(controller.Throttle(3.5), 0.3);
  EXPECT_EQ(controller.Throttle(100), 0.3);
}

TEST(DrivingController, TheSpeedCapCutsTheThrottle) {
  const Controller controller;
  EXPECT_EQ(controller.Throttle(0, 5.0, 5.0), 0.0);            // at the cap
  EXPECT_EQ(controller.Throttle(0, 7.0, 5.0), 0.0);            // above it
  EXPECT_EQ(controller.Throttle(0, 4.9, 5.0), 1.0);            // below it
  EXPECT_EQ(controller.Throttle(0, 99.0, std::nullopt), 1.0);  // no cap
  EXPECT_EQ(controller.Throttle(0, std::nullopt, 5.0), 1.0);   // no speed
  const DriveControls c = controller.FromWaypoints({2, 0.5f, 4, 0, 6, 0, 8, 3}, 6.0, 5.0);
  EXPECT_EQ(c.throttle, 0.0);
  EXPECT_NEAR(c.steering, 0.401, 5e-4);  // steering is not capped
}

TEST(DrivingController, SteeringClampsAtFullLock) {
  const Controller controller;
  EXPECT_EQ(controller.Steering(1, 10), 1.0);  // 84 deg
  EXPECT_EQ(controller.Steering(1, -10), -1.0);
}

TEST(DrivingController, APointBesideOrBehindTheCarGivesFullLockTowardsIt) {
  const Controller controller;
  EXPECT_EQ(controller.Steering(0, 0.5), 1.0);
  EXPECT_EQ(controller.Steering(-3, 0.01), 1.0);
  EXPECT_EQ(controller.Steering(-1, -0.2), -1.0);
  EXPECT_EQ(controller.Steering(0, 0), 0.0);
  EXPECT_EQ(controller.Steering(-2, 0), 0.0);
}

TEST(DrivingController, GainWheelLimitAndThrottleParametersApply) {
  const Controller controller({.max_steering_deg = 45, .gain = 1.5, .t_max = 0.8, .t_min = 0.2, .k = 0.5});
  EXPECT_NEAR(controller.Steering(4, -1), -0.46787478226421597, 1e-12);
  EXPECT_NEAR(controller.Throttle(1.0), 0.3, 1e-12);
  EXPECT_NEAR(controller.Throttle(0.0), 0.8, 1e-12);
  EXPECT_NEAR(controller.Throttle(5.0), 0.2, 1e-12);
}

TEST(DrivingController, NotANumberGivesWhatDrivingControlPyGives) {
  // Python's min/max keep the bound where std::clamp would keep the NaN.
  const Controller controller;
  EXPECT_EQ(controller.Steering(2, kNaN), 1.0);
  EXPECT_EQ(controller.Steering(kNaN, 1), 1.0);
  EXPECT_EQ(controller.Throttle(kNaN), 1.0);
}

TEST(DrivingController, BadParametersAreRefusedNamingThem) {
  const auto message = [](ControllerParams p) {
    try {
      Controller controller(p);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message({.max_steering_deg = 0}), "Controller: max_steering_deg must be positive, got 0");
  EXPECT_EQ(message({.t_max = 0.2}), "Controller: need 0 <= t_min <= t_max <= 1, got 0.3, 0.2");
  EXPECT_EQ(message({.t_max = 1.5}), "Controller: need 0 <= t_min <= t_max <= 1, got 0.3, 1.5");
  EXPECT_EQ(message({.t_min = -0.1}), "Controller: need 0 <= t_min <= t_max <= 1, got -0.1, 1");
  EXPECT_EQ(message({.bend = 1.5}), "Controller: bend must be 0 ... 1, got 1.5");
  EXPECT_EQ(message({.bend = 0.2, .bend_limit = 0}), "Controller: bend_limit must be positive, got 0");
}

}  // namespace
}  // namespace sim4cv::driving

TEST(DrivingControllerTest, SteeringMayAimAtAFartherWaypoint) {
  sim4cv::driving::ControllerParams params;
  params.steer_waypoint = 2;
  const sim4cv::driving::Controller controller(params);
  const sim4cv::driving::Waypoints w{2.0f, 0.5f, 4.0f, 2.0f, 6.0f, 0.0f, 8.0f, 0.0f};
  EXPECT_NEAR(controller.FromWaypoints(w).steering, std::atan(0.5) * 180.0 / 3.14159265358979 / 35.0, 1e-6);
  params.steer_waypoint = 1.5;  // halfway between (2, 0.5) and (4, 2): (3, 1.25), as driving_control.aim_point
  EXPECT_NEAR(sim4cv::driving::Controller(params).FromWaypoints(w).steering,
              std::atan2(1.25, 3.0) * 180.0 / 3.14159265358979 / 35.0, 1e-6);
  params.steer_waypoint = 5;
  try {
    sim4cv::driving::Controller bad(params);
    FAIL() << "steer_waypoint 5 was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "Controller: steer_waypoint must be 1 ... 4, got 5");
  }
}

TEST(DrivingControllerTest, TurnSlowdownLowersTheCapAndBrakesDownToIt) {
  // driving_control's cases (tests/python/test_driving_net.py): the right turn of radius 20 m, h4 = 1.58
  const sim4cv::driving::Waypoints turn{2.00f, 0.10f, 3.97f, 0.40f, 5.91f, 0.89f, 7.79f, 1.58f};
  sim4cv::driving::ControllerParams params;
  params.slowdown = 2.0;
  const sim4cv::driving::Controller controller(params);
  const auto fast = controller.FromWaypoints(turn, 6.0, 8.0);  // cap 8 - 2 * 1.58 = 4.84 m/s
  EXPECT_GT(fast.steering, 0);
  EXPECT_EQ(fast.throttle, 0.0);
  EXPECT_NEAR(fast.brake, 0.5 * (6.0 - (8.0 - 2.0 * 1.58f)), 1e-6);
  const auto slow = controller.FromWaypoints(turn, 4.0, 8.0);
  EXPECT_NEAR(slow.throttle, 1.0 - 0.25 * 1.58f, 1e-6);
  EXPECT_EQ(slow.brake, 0.0);
  EXPECT_EQ(controller.FromWaypoints(turn, 20.0, 8.0).brake, 1.0);
  EXPECT_EQ(sim4cv::driving::Controller().FromWaypoints(turn, 20.0, 8.0).brake, 0.0);  // off by default
  params.slowdown = -1;
  EXPECT_THROW(sim4cv::driving::Controller{params}, std::invalid_argument);
}

TEST(DrivingControllerTest, BendCorrectionMovesTheAimPointOutOfABend) {
  // Waypoints on a right bend of radius 40 m (arc lengths 2, 4, 6, 8 m): the curvature through the first
  // three is 1/40, the chord to the second 3.9933 m, so C = 0.2 moves the aim point 0.2 * 15.987 / 80 =
  // 0.03997 m to the left; the exact values are driving_control.py's from the same float inputs.
  const sim4cv::driving::Waypoints bend{1.999167f, 0.049990f, 3.993337f, 0.199833f,
                                        5.977525f, 0.449157f, 7.946773f, 0.797337f};
  sim4cv::driving::ControllerParams params;
  params.steer_waypoint = 2;
  params.gain = 0.9;
  EXPECT_NEAR(sim4cv::driving::Controller(params).FromWaypoints(bend).steering, 0.07366585659428386, 1e-15);
  params.bend = 0.2;
  params.bend_limit = 1.5;
  const sim4cv::driving::Controller controller(params);
  EXPECT_NEAR(controller.BendShift(bend, bend[2], bend[3]), -0.03997, 1e-5);
  EXPECT_NEAR(controller.BendShift(bend, bend[2], bend[3]), -0.039967218370067864, 1e-15);
  EXPECT_NEAR(controller.FromWaypoints(bend).steering, 0.05895013835340126, 1e-15);
  sim4cv::driving::Waypoints left = bend;  // the same bend to the left: moved right by as much
  for (int i = 1; i < 8; i += 2) left[i] = -left[i];
  EXPECT_NEAR(controller.BendShift(left, left[2], left[3]), 0.039967218370067864, 1e-15);
  params.bend_limit = 0.7;  // |h4| = 0.797 beyond the limit: no correction
  EXPECT_EQ(sim4cv::driving::Controller(params).BendShift(bend, bend[2], bend[3]), 0.0);
}
