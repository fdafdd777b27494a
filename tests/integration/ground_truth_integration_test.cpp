// Ground truth against the real daemon: boxes agree with the mask, contain the
// car where geometry says it is, and depth agrees with the camera geometry.
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

struct Pixel {
  double u, v, depth;
};

// Projects a world point into the UAV camera as the default scene mounts it:
// 0.3 m below the UAV, gimbal 60 degrees down, yawed with the UAV, fov_y 60.
Pixel ProjectIntoUavCamera(const proto::EntityState& uav, const Eigen::Vector3d& point, double width, double height) {
  const Eigen::Quaterniond q(uav.orientation().w(), uav.orientation().x(), uav.orientation().y(), uav.orientation().z());
  const Eigen::Vector3d forward_body = q * Eigen::Vector3d::UnitX();
  const double yaw = std::atan2(forward_body.y(), forward_body.x());
  const double pitch = 60.0 * std::numbers::pi / 180.0;
  const Eigen::Vector3d eye(uav.position().x(), uav.position().y(), uav.position().z() - 0.3);
  const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), -std::sin(pitch));
  const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
  const Eigen::Vector3d up = right.cross(forward);
  const Eigen::Vector3d d = point - eye;
  const double z = d.dot(forward);
  const double focal = (height / 2.0) / std::tan(30.0 * std::numbers::pi / 180.0);
  return {width / 2.0 + focal * d.dot(right) / z, height / 2.0 - focal * d.dot(up) / z, z};
}

TEST_F(DaemonTest, CarBoxContainsTheCarAndMatchesTheMask) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  for (int step = 0; step < 90; ++step) {
    const proto::Frame& frame = client->StepAndReceive();
    const auto mask = FindImage(frame, proto::CHANNEL_MASK);
    const auto depth = FindImage(frame, proto::CHANNEL_DEPTH);
    ASSERT_TRUE(mask && depth);
    const proto::Box* car_box = nullptr;
    for (const auto& box : frame.boxes()) {
      if (box.object_id() == 1) car_box = &box;
    }
    ASSERT_NE(car_box, nullptr) << "frame " << frame.frame_id() << ": the followed car must be in view";
    EXPECT_EQ(car_box->object_class(), proto::OBJECT_CLASS_CAR);
    EXPECT_GT(car_box->visibility(), 0.99f) << "nothing occludes the car from above";

    // The box is the tight box of the car's mask pixels.
    const auto* ids = reinterpret_cast<const uint16_t*>(mask->data);
    uint32_t count = 0, x_min = UINT32_MAX, y_min = UINT32_MAX, x_max = 0, y_max = 0;
    for (uint32_t y = 0; y < frame.height(); ++y) {
      for (uint32_t x = 0; x < frame.width(); ++x) {
        if (ids[y * frame.width() + x] != 1) continue;
        ++count;
        x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, y), y_max = std::max(y_max, y);
      }
    }
    EXPECT_EQ(count, car_box->visible_pixels());
    EXPECT_EQ(car_box->x(), x_min);
    EXPECT_EQ(car_box->y(), y_min);
    EXPECT_EQ(car_box->width(), x_max - x_min + 1);
    EXPECT_EQ(car_box->height(), y_max - y_min + 1);

    // The car's centre, projected with the camera geometry, lies in the box,
    // and the depth there is the distance along the optical axis to the car's surface.
    const auto& car = frame.state().entities(0);
    const auto& uav = frame.state().entities(1);
    const Pixel centre = ProjectIntoUavCamera(uav, {car.position().x(), car.position().y(), car.position().z()},
                                              frame.width(), frame.height());
    EXPECT_GE(centre.u, car_box->x());
    EXPECT_LE(centre.u, car_box->x() + car_box->width());
    EXPECT_GE(centre.v, car_box->y());
    EXPECT_LE(centre.v, car_box->y() + car_box->height());
    const auto* metres = reinterpret_cast<const float*>(depth->data);
    const float depth_at_centre =
        metres[static_cast<uint32_t>(centre.v) * frame.width() + static_cast<uint32_t>(centre.u)];
    EXPECT_LT(depth_at_centre, centre.depth) << "the roof is nearer than the centre";
    EXPECT_GT(depth_at_centre, centre.depth - 1.5);
  }
}

}  // namespace
}  // namespace sim4cv::testing
