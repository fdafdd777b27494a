// Configure against the real daemon: cameras added on a spawned UAV, fixed in
// the world, as a stereo pair, and removed while clients watch them (default
// scene: the car, object id 1, drives east from (-40, -42)).
#include <cmath>

#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

constexpr uint32_t kCarId = 1;

class CamerasTest : public ConfigureTest {
 protected:
  void SetUp() override {
    StartDaemon();
    client_ = Connect("configure");
  }

  std::unique_ptr<Client> client_;
};

TEST_F(CamerasTest, CameraOnASpawnedUavDeliversFramesOfItsSize) {
  const uint32_t uav = client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -40, -60, 20, 90);
  const proto::WorldInfo world = client_->AddCamera(
      {.name = "uav_b_cam", .mounted_on = "uav_b", .width = 160, .height = 120, .fov_y_deg = 70, .pitch_down_deg = 30});
  ASSERT_TRUE(HasCamera(world, "uav_b_cam")) << world.ShortDebugString();
  const proto::CameraInfo& info = world.cameras(world.cameras_size() - 1);
  EXPECT_EQ(info.width(), 160u);
  EXPECT_EQ(info.height(), 120u);
  EXPECT_DOUBLE_EQ(info.fov_y_deg(), 70);
  EXPECT_EQ(info.mounted_on(), "uav_b");
  const auto late = Connect("late");
  ASSERT_EQ(late->welcome().cameras_size(), world.cameras_size());
  EXPECT_EQ(late->welcome().cameras(world.cameras_size() - 1).name(), "uav_b_cam") << "a new Welcome lists it";

  client_->Subscribe("uav_b_cam", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  for (int i = 0; i < 5; ++i) {
    const proto::Frame& frame = client_->StepAndReceive();
    EXPECT_EQ(frame.camera(), "uav_b_cam");
    ASSERT_EQ(frame.width(), 160u);
    ASSERT_EQ(frame.height(), 120u);
    const auto rgb = FindImage(frame, proto::CHANNEL_RGB);
    ASSERT_TRUE(rgb.has_value());
    EXPECT_EQ(rgb->stride, 160u * 3);
    EXPECT_EQ(frame.images(0).data().size(), 160u * 120 * 3);
    EXPECT_EQ(frame.camera_intrinsics().width(), 160u);
    // The camera rides the UAV: its centre is the UAV's (offset 0).
    EXPECT_LT(Distance(frame.camera_pose().position(), FindEntity(frame.state(), uav)->position()), 0.01);
  }
}

TEST_F(CamerasTest, WorldFixedCameraWatchesTheCarDriveThrough) {
  // 30 m above the car's start, looking straight down: about 46 x 35 m of road.
  client_->AddCamera(
      {.name = "road_cam", .width = 160, .height = 120, .pitch_down_deg = 90, .x = -40, .y = -42, .z = 30});
  client_->Subscribe("road_cam", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  int frames_with_car = 0;
  bool first_has_car = false, last_has_car = true;
  for (int i = 1; i <= 300; ++i) {  // 10 s at 6 m/s: the car leaves the view
    const proto::Frame& frame = client_->StepAndReceive();
    const bool seen = BoxOf(frame, kCarId).has_value();
    frames_with_car += seen;
    if (i == 1) first_has_car = seen;
    if (i == 300) last_has_car = seen;
    EXPECT_LT(Distance(frame.camera_pose().position(), Vec(-40, -42, 30)), 1e-3) << "frame " << i;
  }
  EXPECT_TRUE(first_has_car) << "the car starts right below the camera";
  EXPECT_FALSE(last_has_car) << "the camera stays where it is while the car drives away";
  EXPECT_GT(frames_with_car, 30);
}

// A dataset generator moves one world-fixed camera from view to view.
TEST_F(CamerasTest, SetCameraPoseMovesAWorldFixedCameraFromTheNextFrameOn) {
  client_->AddCamera(
      {.name = "road_cam", .width = 160, .height = 120, .pitch_down_deg = 90, .x = -40, .y = -42, .z = 30});
  client_->Subscribe("road_cam", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  EXPECT_LT(Distance(client_->StepAndReceive().camera_pose().position(), Vec(-40, -42, 30)), 1e-3);
  client_->SetCameraPose("road_cam", 10, 20, 2, 45, 5);
  const proto::Frame& moved = client_->StepAndReceive();
  EXPECT_LT(Distance(moved.camera_pose().position(), Vec(10, 20, 2)), 1e-3);
  try {
    client_->SetCameraPose("uav", 0, 0, 10, 0);
    FAIL() << "a mounted camera was moved";
  } catch (const ServerError& e) {
    EXPECT_EQ(e.code(), proto::ERROR_CODE_INVALID_ARGUMENT);
    EXPECT_NE(std::string(e.what()).find("SetCameraPose moves cameras fixed in the world; 'uav' is mounted on 'uav'"),
              std::string::npos)
        << e.what();
  }
  try {
    client_->SetCameraPose("nowhere", 0, 0, 10, 0);
    FAIL() << "an unknown camera was moved";
  } catch (const ServerError& e) {
    EXPECT_EQ(e.code(), proto::ERROR_CODE_UNKNOWN_CAMERA);
  }
}

TEST_F(CamerasTest, RemovedCameraSendsItsSubscribersAnError) {
  client_->AddCamera({.name = "side", .mounted_on = "uav", .width = 64, .height = 48, .yaw_deg = 90});
  auto viewer = Connect("viewer");
  viewer->Subscribe("side", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  client_->Subscribe("side", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  for (int i = 0; i < 3; ++i) {
    viewer->Step();
    client_->Step();
    ASSERT_TRUE(viewer->ReceiveFrame(frame, 10s));
    ASSERT_TRUE(client_->ReceiveFrame(frame, 10s));
  }

  // The remover's own subscription ends too: RemoveCamera succeeds and the
  // Error about the subscription surfaces from the next receive.
  const proto::WorldInfo world = client_->RemoveCamera("side");
  EXPECT_FALSE(HasCamera(world, "side"));
  for (Client* subscriber : {client_.get(), viewer.get()}) {
    try {
      subscriber->ReceiveFrame(frame, 10s);
      ADD_FAILURE() << "a subscriber of the removed camera got no Error";
    } catch (const ServerError& error) {
      EXPECT_EQ(error.code(), proto::ERROR_CODE_UNKNOWN_CAMERA) << error.what();
      EXPECT_FALSE(error.fatal());
      EXPECT_EQ(error.request_id(), 0u);
      EXPECT_NE(std::string(error.what()).find("removed"), std::string::npos) << error.what();
    }
  }
  // Its subscribers no longer hold the simulation back, and subscribe again.
  viewer->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  EXPECT_GE(viewer->StepAndReceive().frame_id(), 4u);

  EXPECT_THROW(client_->Subscribe("side", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP), ServerError);
  ExpectRefused([&] { client_->RemoveCamera("side"); }, proto::ERROR_CODE_UNKNOWN_CAMERA, {"'side'"});
  ExpectRefused([&] { client_->RemoveCamera("uav"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"belongs to the scene"});
  ExpectRefused([&] { client_->AddCamera({.name = "cam", .mounted_on = "nobody"}); }, proto::ERROR_CODE_UNKNOWN_ENTITY,
                {"'nobody'", "'uav'"});
  client_->AddCamera({.name = "cam"});
  ExpectRefused([&] { client_->AddCamera({.name = "cam"}); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"'cam'"});
}

TEST_F(CamerasTest, StereoPairOnOneUavSeesTheCarWithDisparity) {
  // Two cameras 0.5 m apart across the scene UAV, which films the car.
  for (const auto& [name, y] : {std::pair{"left", 0.25}, std::pair{"right", -0.25}}) {
    client_->AddCamera({.name = name,
                        .mounted_on = "uav",
                        .width = 160,
                        .height = 120,
                        .pitch_down_deg = 60,
                        .gimbal = true,
                        .y = y,
                        .z = -0.3});
  }
  auto right = Connect("right");
  client_->Subscribe("left", {proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  right->Subscribe("right", {proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  proto::Frame left_frame, right_frame;
  for (int i = 0; i < 10; ++i) {
    client_->Step();
    right->Step();
    ASSERT_TRUE(client_->ReceiveFrame(left_frame, 10s));
    ASSERT_TRUE(right->ReceiveFrame(right_frame, 10s));
    ASSERT_EQ(left_frame.frame_id(), right_frame.frame_id());
  }
  EXPECT_NEAR(Distance(left_frame.camera_pose().position(), right_frame.camera_pose().position()), 0.5, 0.01);
  EXPECT_NE(left_frame.images(0).data(), right_frame.images(0).data()) << "the two images are the same";

  // The car's projection shifts right in the left image by about fx * 0.5 m / depth.
  const auto car_in = [](const proto::Frame& frame) -> const proto::ObjectGroundTruth* {
    for (const auto& object : frame.objects()) {
      if (object.object_id() == kCarId) return &object;
    }
    return nullptr;
  };
  const proto::ObjectGroundTruth* left_car = car_in(left_frame);
  const proto::ObjectGroundTruth* right_car = car_in(right_frame);
  ASSERT_TRUE(left_car && right_car) << "both cameras see the car";
  const auto centre = [](const proto::ImageBox& box) { return box.x() + box.width() / 2; };
  const double disparity = centre(left_car->projected_box()) - centre(right_car->projected_box());
  const double depth = Distance(left_frame.camera_pose().position(), left_car->position());
  const double expected = left_frame.camera_intrinsics().fx() * 0.5 / depth;
  EXPECT_GT(disparity, 0.5 * expected) << "expected about " << expected << " px";
  EXPECT_LT(disparity, 1.5 * expected) << "expected about " << expected << " px";
}

}  // namespace
}  // namespace sim4cv::testing
