// Unit tests of the camera gimbal (server/sim/vehicles/gimbal.*).
#include "server/sim/vehicles/gimbal.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/support/no_warnings.h"

namespace sim4cv::vehicles {
namespace {

using Eigen::AngleAxisd;
using Eigen::Quaterniond;
using Eigen::Vector3d;
constexpr double kDeg = std::numbers::pi / 180;

// Body orientation from yaw, pitch (about y, nose down) and roll (about x),
// applied in that order (z-y-x Euler): its heading is exactly `yaw`.
Quaterniond Body(double yaw_deg, double pitch_deg, double roll_deg) {
  return Quaterniond(AngleAxisd(yaw_deg * kDeg, Vector3d::UnitZ()) * AngleAxisd(pitch_deg * kDeg, Vector3d::UnitY()) *
                     AngleAxisd(roll_deg * kDeg, Vector3d::UnitX()));
}

// Exact to rounding: the orientations below are products of a handful of
// sines and cosines.
constexpr double kTolerance = 1e-12;

TEST(GimbalTest, LevelBodyLooksPitchDownAlongItsHeading) {
  const Pose body{{10, -4, 15}, Body(30, 0, 0)};
  const Pose camera = GimbalCameraPose(body);
  const Vector3d forward = camera.orientation * Vector3d::UnitX();
  EXPECT_NEAR((forward - Vector3d(std::cos(30 * kDeg) * std::cos(60 * kDeg), std::sin(30 * kDeg) * std::cos(60 * kDeg),
                                  -std::sin(60 * kDeg)))
                  .norm(),
              0.0, kTolerance);
  // Image up tilts forward; image left stays horizontal.
  EXPECT_GT((camera.orientation * Vector3d::UnitZ()).z(), 0.0);
  EXPECT_NEAR((camera.orientation * Vector3d::UnitY()).z(), 0.0, kTolerance);
  EXPECT_NEAR((camera.position - Vector3d(10, -4, 14.7)).norm(), 0.0, kTolerance) << "hangs 0.3 m below";
}

TEST(GimbalTest, BodyRollAndPitchLeaveTheCameraOrientationAlone) {
  const Pose level{{0, 0, 20}, Body(-75, 0, 0)};
  const Quaterniond reference = GimbalCameraPose(level).orientation;
  for (double pitch : {-25.0, -10.0, 0.0, 15.0, 25.0}) {
    for (double roll : {-25.0, 0.0, 7.5, 25.0}) {
      const Pose tilted{{0, 0, 20}, Body(-75, pitch, roll)};
      const Quaterniond camera = GimbalCameraPose(tilted).orientation;
      EXPECT_NEAR(camera.angularDistance(reference), 0.0, kTolerance) << "pitch " << pitch << " roll " << roll;
      // Not an accident of this reference: the body itself is tilted.
      if (pitch != 0 || roll != 0) {
        EXPECT_GT(tilted.orientation.angularDistance(level.orientation), 0.1);
      }
    }
  }
}

TEST(GimbalTest, CameraFollowsOnlyTheYaw) {
  for (double yaw : {-170.0, -90.0, 0.0, 45.0, 179.0}) {
    const Pose camera = GimbalCameraPose({{0, 0, 0}, Body(yaw, 20, -15)}, {35.0, Vector3d::Zero()});
    const Vector3d forward = camera.orientation * Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(forward.y(), forward.x()), yaw * kDeg, kTolerance);
    EXPECT_NEAR(std::asin(-forward.z()), 35 * kDeg, kTolerance) << "the gimbal's pitch, not the body's";
  }
}

TEST(GimbalTest, MountOffsetIsFixedToTheFrame) {
  // The gimbal hangs from the frame: a rolled body swings it sideways.
  const Pose body{{1, 2, 10}, Body(0, 0, 30)};
  const Pose camera = GimbalCameraPose(body);
  EXPECT_NEAR((camera.position - (Vector3d(1, 2, 10) + body.orientation * Vector3d(0, 0, -0.3))).norm(), 0.0,
              kTolerance);
  EXPECT_GT(camera.position.y(), 2.1) << "rolled right-side down about +x, the point below swings to +y";
}

TEST(GimbalTest, NinetyDegreesLooksStraightDownWithTheHeadingUpInTheImage) {
  const Pose camera = GimbalCameraPose({{0, 0, 30}, Body(120, 10, 5)}, {90.0, Vector3d::Zero()});
  EXPECT_NEAR(((camera.orientation * Vector3d::UnitX()) - Vector3d(0, 0, -1)).norm(), 0.0, kTolerance);
  const Vector3d up = camera.orientation * Vector3d::UnitZ();
  EXPECT_NEAR((up - Vector3d(std::cos(120 * kDeg), std::sin(120 * kDeg), 0)).norm(), 0.0, kTolerance);
}

}  // namespace
}  // namespace sim4cv::vehicles
