// The handshake, subscription and lockstep stepping against the real daemon.
#include <chrono>
#include <cmath>
#include <thread>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

TEST_F(DaemonTest, ListeningLineAndWelcomeDescribeTheScene) {
  StartDaemon({"--width", "160", "--height", "96"});
  const std::string udp_port = ListeningField(daemon_->listening_line(), "udp");  // UDP is on by default
  EXPECT_EQ(daemon_->listening_line(),
            "sim4cvd listening tcp=" + std::to_string(daemon_->tcp_port()) + " udp=" + udp_port);
  auto client = Connect("welcome-test");
  const proto::Welcome& welcome = client->welcome();
  EXPECT_EQ(welcome.protocol_version(), 1u);
  EXPECT_EQ(welcome.scene_name(), "default");
  ASSERT_EQ(welcome.cameras_size(), 3);
  EXPECT_EQ(welcome.cameras(0).name(), "uav");
  EXPECT_EQ(welcome.cameras(0).mounted_on(), "uav");
  EXPECT_EQ(welcome.cameras(1).name(), "car_front");
  EXPECT_EQ(welcome.cameras(2).name(), "car_chase");
  EXPECT_EQ(welcome.cameras(2).mounted_on(), "car");
  for (const auto& camera : welcome.cameras()) {
    EXPECT_EQ(camera.width(), 160u);
    EXPECT_EQ(camera.height(), 96u);
  }
  EXPECT_EQ(welcome.mode(), proto::SIM_MODE_LOCKSTEP);
  EXPECT_DOUBLE_EQ(welcome.physics_hz(), 240.0);
  EXPECT_DOUBLE_EQ(welcome.frame_hz(), 30.0);
  ASSERT_EQ(welcome.transports_size(), 2);
  EXPECT_EQ(welcome.transports(0).kind(), proto::TRANSPORT_KIND_TCP);
  EXPECT_EQ(welcome.transports(0).address(), std::to_string(daemon_->tcp_port()));
  EXPECT_EQ(welcome.transports(1).kind(), proto::TRANSPORT_KIND_UDP);
  EXPECT_EQ(welcome.transports(1).address(), udp_port);
  ASSERT_EQ(welcome.entities_size(), 2);
  EXPECT_EQ(welcome.entities(0).name(), "car");
  EXPECT_EQ(welcome.entities(0).kind(), proto::ENTITY_KIND_CAR);
  EXPECT_GT(welcome.client_id(), 0u);
}

TEST_F(DaemonTest, VersionMismatchIsRefusedNamingBothVersions) {
  StartDaemon();
  Client client;
  try {
    client.Connect("127.0.0.1", daemon_->tcp_port(), "old", Client::Duration(5000), 7);
    FAIL() << "a version-7 Hello was accepted";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_VERSION_MISMATCH);
    EXPECT_TRUE(error.fatal());
    EXPECT_NE(std::string(error.what()).find("version 7"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("version 1"), std::string::npos) << error.what();
  }
  auto other = Connect();  // the daemon still serves
  EXPECT_EQ(other->welcome().scene_name(), "default");
}

TEST_F(DaemonTest, LockstepFramesCarryEveryChannelInOrder) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("uav", {proto::CHANNEL_MASK, proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_BOXES},
                    proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  for (uint64_t expected_id = 1; expected_id <= 20; ++expected_id) {
    const proto::Frame& frame = client->StepAndReceive();
    ASSERT_EQ(frame.frame_id(), expected_id);
    EXPECT_NEAR(frame.sim_time(), static_cast<double>(expected_id) / 30.0, 1e-9);
    EXPECT_EQ(frame.camera(), "uav");
    ASSERT_EQ(frame.images_size(), 3);
    EXPECT_EQ(frame.images(0).channel(), proto::CHANNEL_MASK);
    EXPECT_EQ(frame.images(1).channel(), proto::CHANNEL_RGB);
    EXPECT_EQ(frame.images(2).channel(), proto::CHANNEL_DEPTH);
    EXPECT_EQ(frame.images(0).data().size(), 320u * 180 * 2);
    EXPECT_EQ(frame.images(1).data().size(), 320u * 180 * 3);
    EXPECT_EQ(frame.images(2).data().size(), 320u * 180 * 4);
    EXPECT_EQ(frame.images(1).stride(), 320u * 3);
    EXPECT_EQ(frame.state().frame_id(), expected_id);
    EXPECT_FALSE(frame.boxes().empty());
    EXPECT_EQ(frame.dropped_frames(), 0u);
  }
}

TEST_F(DaemonTest, LockstepWaitsForEveryClientAndNotForOneThatLeft) {
  StartDaemon();
  auto a = Connect("a");
  auto b = Connect("b");
  a->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  b->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  a->Step();
  EXPECT_FALSE(a->ReceiveFrame(frame, 300ms)) << "the simulation advanced without b's Step";
  b->Step();
  ASSERT_TRUE(a->ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), 1u);
  ASSERT_TRUE(b->ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), 1u);

  a->Step();
  b->Close();  // b goes away without stepping: a must not wait for it
  ASSERT_TRUE(a->ReceiveFrame(frame, 5000ms)) << "lockstep stalled on a client that disconnected";
  EXPECT_EQ(frame.frame_id(), 2u);
}

TEST_F(DaemonTest, CarCamerasSeeTheRoadAndTheChaseCameraSeesTheCar) {
  StartDaemon();
  auto front = Connect("front");
  auto chase = Connect("chase");
  front->Subscribe("car_front", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH}, proto::DELIVERY_LOCKSTEP);
  chase->Subscribe("car_chase", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 30; ++i) {
    front->Step();
    chase->Step();
    proto::Frame front_frame, chase_frame;
    ASSERT_TRUE(front->ReceiveFrame(front_frame, 5000ms));
    ASSERT_TRUE(chase->ReceiveFrame(chase_frame, 5000ms));
    EXPECT_EQ(front_frame.frame_id(), chase_frame.frame_id());
    EXPECT_EQ(front_frame.camera(), "car_front");
    // The chase camera, 9 m behind and 3 m above, always has the car in view.
    bool car_seen = false;
    for (const auto& box : chase_frame.boxes()) car_seen = car_seen || box.object_id() == 1;
    EXPECT_TRUE(car_seen) << "frame " << chase_frame.frame_id();
    // The first-person camera looks down the road: the bottom row's depth is
    // a few metres (the road just ahead), not infinite.
    const auto depth = FindImage(front_frame, proto::CHANNEL_DEPTH);
    ASSERT_TRUE(depth);
    const auto* metres = reinterpret_cast<const float*>(depth->data);
    const float bottom_centre = metres[(front_frame.height() - 1) * front_frame.width() + front_frame.width() / 2];
    EXPECT_GT(bottom_centre, 0.5f);
    EXPECT_LT(bottom_centre, 20.0f);
  }
}

TEST_F(DaemonTest, NewestFrameSubscriberInLockstepSeesTheLockstepFrames) {
  StartDaemon();
  auto stepper = Connect("stepper");
  auto watcher = Connect("watcher");
  stepper->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  watcher->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST);
  stepper->StepAndReceive();
  proto::Frame frame;
  ASSERT_TRUE(watcher->ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), 1u);
  EXPECT_EQ(frame.images_size(), 1);
  EXPECT_EQ(frame.boxes_size(), 0) << "boxes were not subscribed";
}

TEST_F(DaemonTest, StateAndTrackerOutputAndControlsAreApplied) {
  StartDaemon();
  auto client = Connect();
  client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 30; ++i) client->StepAndReceive();
  proto::State state = client->GetState();
  EXPECT_EQ(state.frame_id(), 30u);
  ASSERT_EQ(state.entities_size(), 2);
  const double speed_before = std::hypot(state.entities(0).linear_velocity().x(), state.entities(0).linear_velocity().y());
  EXPECT_GT(speed_before, 1.0) << "the waypoint follower should have the car moving";

  client->SendTrackerOutput(30, 10.5f, 20.f, 30.f, 40.f, 0.75f);
  client->SendControls(1, 0.f, 0.f, 1.f);
  for (int i = 0; i < 60; ++i) client->StepAndReceive();
  state = client->GetState();
  EXPECT_EQ(state.last_tracker_output().frame_id(), 30u);
  EXPECT_FLOAT_EQ(state.last_tracker_output().box().x(), 10.5f);
  EXPECT_FLOAT_EQ(state.last_tracker_output().confidence(), 0.75f);
  const double speed_after = std::hypot(state.entities(0).linear_velocity().x(), state.entities(0).linear_velocity().y());
  EXPECT_LT(speed_after, 0.1) << "full brake for 2 s should stop the car";
}

}  // namespace
}  // namespace sim4cv::testing
