// Ground truth against the real daemon: boxes agree with the mask; the camera
// model sent with each frame (intrinsics and pose) puts the car where its box
// and the depth image say; the projected 3D boxes contain the visible ones.
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

constexpr uint32_t kCarId = 1;
constexpr uint32_t kFirstBuildingId = 100;

Eigen::Vector3d ToEigen(const proto::Vec3& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Quaterniond ToEigen(const proto::Quaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }

struct Pixel {
  double u, v, depth;
};

// Projects a world point with nothing but what the frame carries, as
// docs/protocol.md §9 tells a client to.
Pixel Project(const proto::Frame& frame, const Eigen::Vector3d& world) {
  const proto::CameraIntrinsics& k = frame.camera_intrinsics();
  const Eigen::Vector3d p = ToEigen(frame.camera_pose().orientation()).inverse() *
                            (world - ToEigen(frame.camera_pose().position()));
  return {k.fx() * p.x() / p.z() + k.cx(), k.fy() * p.y() / p.z() + k.cy(), p.z()};
}

template <typename Message>
const Message* FindById(const google::protobuf::RepeatedPtrField<Message>& list, uint32_t id) {
  for (const Message& m : list) {
    if (m.object_id() == id) return &m;
  }
  return nullptr;
}

// The visible box lies inside the projected one; pixel edges may stick out
// by half a pixel (a pixel is drawn when its centre is covered).
void ExpectProjectedContainsVisible(const proto::ObjectGroundTruth& object, const proto::Box& box) {
  const proto::ImageBox& p = object.projected_box();
  SCOPED_TRACE(::testing::Message() << "object " << object.object_id() << ": visible " << box.x() << "," << box.y()
                                    << " " << box.width() << "x" << box.height() << ", projected " << p.x() << ","
                                    << p.y() << " " << p.width() << "x" << p.height());
  EXPECT_TRUE(object.has_visible_box());
  EXPECT_GE(box.x(), p.x() - 1.0);
  EXPECT_GE(box.y(), p.y() - 1.0);
  EXPECT_LE(box.x() + box.width(), p.x() + p.width() + 1.0);
  EXPECT_LE(box.y() + box.height(), p.y() + p.height() + 1.0);
}

TEST_F(DaemonTest, CarBoxContainsTheCarAndMatchesTheMask) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  for (int step = 0; step < 90; ++step) {
    const proto::Frame& frame = client->StepAndReceive();
    SCOPED_TRACE(::testing::Message() << "frame " << frame.frame_id());
    const auto mask = FindImage(frame, proto::CHANNEL_MASK);
    const auto depth = FindImage(frame, proto::CHANNEL_DEPTH);
    ASSERT_TRUE(mask && depth);
    const proto::Box* car_box = FindById(frame.boxes(), kCarId);
    ASSERT_NE(car_box, nullptr) << "the followed car must be in view";
    EXPECT_EQ(car_box->object_class(), proto::OBJECT_CLASS_CAR);
    EXPECT_GT(car_box->visibility(), 0.99f) << "nothing occludes the car from above";

    // The box is the tight box of the car's mask pixels.
    const auto* ids = reinterpret_cast<const uint16_t*>(mask->data);
    uint32_t count = 0, x_min = UINT32_MAX, y_min = UINT32_MAX, x_max = 0, y_max = 0;
    for (uint32_t y = 0; y < frame.height(); ++y) {
      for (uint32_t x = 0; x < frame.width(); ++x) {
        if (ids[y * frame.width() + x] != kCarId) continue;
        ++count;
        x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, y), y_max = std::max(y_max, y);
      }
    }
    EXPECT_EQ(count, car_box->visible_pixels());
    EXPECT_EQ(car_box->x(), x_min);
    EXPECT_EQ(car_box->y(), y_min);
    EXPECT_EQ(car_box->width(), x_max - x_min + 1);
    EXPECT_EQ(car_box->height(), y_max - y_min + 1);

    // Square pixels, principal point at the centre, fov_y 60 degrees.
    const proto::CameraIntrinsics& k = frame.camera_intrinsics();
    EXPECT_NEAR(k.fx(), 90.0 / std::tan(30.0 * std::numbers::pi / 180.0), 1e-6);
    EXPECT_EQ(k.fy(), k.fx());
    EXPECT_EQ(k.cx(), frame.width() / 2.0);
    EXPECT_EQ(k.cy(), frame.height() / 2.0);

    // The car's 3D ground truth is its State, and its projected 3D box holds its visible box.
    const proto::EntityState& car = frame.state().entities(0);
    const proto::ObjectGroundTruth* car_3d = FindById(frame.objects(), kCarId);
    ASSERT_NE(car_3d, nullptr);
    EXPECT_EQ(car_3d->object_class(), proto::OBJECT_CLASS_CAR);
    EXPECT_LT((ToEigen(car_3d->position()) - ToEigen(car.position())).norm(), 1e-9);
    EXPECT_LT(ToEigen(car_3d->orientation()).angularDistance(ToEigen(car.orientation())), 1e-9);
    EXPECT_LT((ToEigen(car_3d->linear_velocity()) - ToEigen(car.linear_velocity())).norm(), 1e-9);
    EXPECT_LT((ToEigen(car_3d->half_extents()) - Eigen::Vector3d(2.25, 0.9, 0.6)).norm(), 1e-9);
    ExpectProjectedContainsVisible(*car_3d, *car_box);

    // The car's centre, projected with the sent camera model, lies in its box,
    // and the depth there is the distance along the optical axis to the car's surface.
    const Pixel centre = Project(frame, ToEigen(car.position()));
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

// docs/scenes.md: car_chase sits at (-9, 0, 3) m in the car's body frame,
// pitched 15 degrees down, with no roll.
TEST_F(DaemonTest, ChaseCameraRidesNineMetresBehindAndThreeAboveTheCar) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("car_chase", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  const double pitch = 15.0 * std::numbers::pi / 180.0;
  for (int step = 0; step < 30; ++step) {
    const proto::Frame& frame = client->StepAndReceive();
    SCOPED_TRACE(::testing::Message() << "frame " << frame.frame_id());
    const proto::EntityState& car = frame.state().entities(0);
    const Eigen::Quaterniond car_orientation = ToEigen(car.orientation());
    const Eigen::Vector3d expected = ToEigen(car.position()) + car_orientation * Eigen::Vector3d(-9, 0, 3);
    EXPECT_LT((ToEigen(frame.camera_pose().position()) - expected).norm(), 1e-3);
    // OpenCV axes: z along the optical axis, x to the car's right, y down in the image.
    const Eigen::Quaterniond camera = ToEigen(frame.camera_pose().orientation());
    const Eigen::Vector3d forward = car_orientation * Eigen::Vector3d(std::cos(pitch), 0, -std::sin(pitch));
    EXPECT_LT((camera * Eigen::Vector3d::UnitZ() - forward).norm(), 1e-5);
    EXPECT_LT((camera * Eigen::Vector3d::UnitX() - car_orientation * Eigen::Vector3d(0, -1, 0)).norm(), 1e-5);
    // The camera sees the car it chases straight ahead, slightly below the image's middle.
    const Pixel car_pixel = Project(frame, ToEigen(car.position()));
    EXPECT_NEAR(car_pixel.u, frame.width() / 2.0, 1.0);
    EXPECT_GT(car_pixel.v, frame.height() / 2.0);
  }
}

// From behind the car, the buildings along the road hide parts of each
// other: their 3D boxes reach beyond what is visible.
TEST_F(DaemonTest, PartlyOccludedBuildingProjectsLargerThanItsVisibleBox) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("car_chase", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/false);
  int partly_occluded = 0;
  for (int step = 0; step < 10; ++step) {
    const proto::Frame& frame = client->StepAndReceive();
    SCOPED_TRACE(::testing::Message() << "frame " << frame.frame_id());
    for (const proto::Box& box : frame.boxes()) {
      const proto::ObjectGroundTruth* object = FindById(frame.objects(), box.object_id());
      ASSERT_NE(object, nullptr) << "every Box has its 3D ground truth";
      ExpectProjectedContainsVisible(*object, box);
      if (box.object_id() < kFirstBuildingId || box.visibility() > 0.8f) continue;
      ++partly_occluded;
      EXPECT_EQ(object->object_class(), proto::OBJECT_CLASS_BUILDING);
      const double visible_area = static_cast<double>(box.width()) * box.height();
      EXPECT_GT(object->projected_box().width() * object->projected_box().height(), 1.2 * visible_area);
    }
    for (const proto::ObjectGroundTruth& object : frame.objects()) {
      EXPECT_EQ(object.has_visible_box(), FindById(frame.boxes(), object.object_id()) != nullptr);
      EXPECT_GT(object.projected_box().width(), 0.0f);
      EXPECT_GT(object.projected_box().height(), 0.0f);
      if (object.object_id() >= kFirstBuildingId) {
        EXPECT_TRUE(ToEigen(object.linear_velocity()).isZero(0.0)) << "buildings stand still";
      }
    }
  }
  EXPECT_GT(partly_occluded, 0) << "the default scene's chase view shows buildings behind buildings";
}

}  // namespace
}  // namespace sim4cv::testing

namespace sim4cv::testing {
namespace {

// The dense channels of a live frame agree with each other and with the
// mask: sky (infinite depth) is class 10 with zero normals and zero flow;
// every surface has a unit normal facing the camera and a finite flow; the
// car's mask pixels are class car (13); the UAV follows the car, so the
// car's pixels move less than the ground's.
TEST_F(DaemonTest, DenseChannelsAgreeWithDepthAndMask) {
  StartDaemon();
  auto client = Connect("channels");
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 40; ++i) client->StepAndReceive();  // under way: the camera and the car move
  const proto::Frame& frame = client->StepAndReceive();
  const auto depth = FindImage(frame, proto::CHANNEL_DEPTH), mask = FindImage(frame, proto::CHANNEL_MASK);
  const auto semantic = FindImage(frame, proto::CHANNEL_SEMANTIC), normals = FindImage(frame, proto::CHANNEL_NORMALS);
  const auto flow = FindImage(frame, proto::CHANNEL_FLOW);
  ASSERT_TRUE(depth && mask && semantic && normals && flow);
  EXPECT_EQ(semantic->element, proto::ELEMENT_TYPE_U8);
  EXPECT_EQ(normals->components, 3u);
  EXPECT_EQ(flow->components, 2u);
  uint32_t car_pixels = 0, sky_pixels = 0;
  double car_flow = 0, ground_flow = 0;
  uint32_t ground_pixels = 0;
  for (uint32_t y = 0; y < frame.height(); ++y) {
    for (uint32_t x = 0; x < frame.width(); ++x) {
      const float d = *depth->at<float>(x, y);
      const uint8_t cls = *semantic->at<uint8_t>(x, y);
      const float* n = normals->at<float>(x, y);
      const float* f = flow->at<float>(x, y);
      if (std::isinf(d)) {
        ++sky_pixels;
        ASSERT_EQ(cls, 10) << x << "," << y;
        ASSERT_TRUE(n[0] == 0 && n[1] == 0 && n[2] == 0 && f[0] == 0 && f[1] == 0) << x << "," << y;
        continue;
      }
      ASSERT_NE(cls, 10) << "a surface labelled sky at " << x << "," << y;
      ASSERT_NE(cls, 255) << "an unlabelled surface at " << x << "," << y;
      ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0, 1e-3) << x << "," << y;
      ASSERT_LT(n[2], 0.05f) << "a normal facing away from the camera at " << x << "," << y;
      ASSERT_TRUE(std::isfinite(f[0]) && std::isfinite(f[1])) << x << "," << y;
      const double moved = std::hypot(f[0], f[1]);
      if (*mask->at<uint16_t>(x, y) == kCarId) {
        ++car_pixels;
        car_flow += moved;
        ASSERT_EQ(cls, 13) << "the car's pixel " << x << "," << y;
      } else if (cls == 0 || cls == 9) {
        ++ground_pixels;
        ground_flow += moved;
      }
    }
  }
  EXPECT_GT(car_pixels, 50u);
  EXPECT_GT(ground_pixels, 1000u);
  EXPECT_LT(car_flow / car_pixels, ground_flow / ground_pixels)
      << "the camera tracks the car, so the car should move less in the image than the ground";
  (void)sky_pixels;  // the default UAV view may or may not see the horizon
}

}  // namespace
}  // namespace sim4cv::testing
