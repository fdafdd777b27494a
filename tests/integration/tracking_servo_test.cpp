// Tracking in the loop (docs/tracking.md, "The servo"): a UAV ordered to
// track steers by the boxes its camera's tracker sends. The ground-truth
// tracker (each frame's true box of the car) must keep the car in view
// around the default scene's loop; the gains of server/sim/track_servo.h
// are tuned with this test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

uint32_t IdOf(const proto::WorldInfo& world, const std::string& name) {
  for (const auto& entity : world.entities()) {
    if (entity.name() == name) return entity.id();
  }
  ADD_FAILURE() << "no entity " << name;
  return 0;
}

const proto::Box* BoxOf(const proto::Frame& frame, uint32_t id) {
  for (const proto::Box& box : frame.boxes()) {
    if (box.object_id() == id) return &box;
  }
  return nullptr;
}

double Distance(const proto::State& state, uint32_t a, uint32_t b) {
  const proto::EntityState* pa = nullptr;
  const proto::EntityState* pb = nullptr;
  for (const auto& e : state.entities()) {
    if (e.id() == a) pa = &e;
    if (e.id() == b) pb = &e;
  }
  if (!pa || !pb) return -1;
  const auto& p = pa->position();
  const auto& q = pb->position();
  return std::hypot(p.x() - q.x(), p.y() - q.y(), p.z() - q.z());
}

class TrackingServoTest : public DaemonTest {
 protected:
  void SetUp() override { Start({}); }
  void Start(std::vector<std::string> args) {
    if (daemon_) {
      EXPECT_EQ(daemon_->Stop(), 0);
    }
    args.insert(args.end(), {"--mode", "lockstep"});
    StartDaemon(args);
    client_ = Connect("servo");
    const proto::WorldInfo world = client_->GetWorld();
    car_ = IdOf(world, "car");
    uav_ = IdOf(world, "uav");
  }
  // Flies `frames` frames with the ground-truth tracker (the visible box;
  // nothing while a building hides the car: the servo coasts on its
  // estimate); expects the car in view, hidden never longer than a second
  // (the lost-target rule's default), and near the image centre.
  void FlyWithGroundTruth(int frames, double max_mean_offset);

  std::unique_ptr<Client> client_;
  uint32_t car_ = 0, uav_ = 0;
};

void TrackingServoTest::FlyWithGroundTruth(int frames, double max_mean_offset) {
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  client_->StepAndReceive();
  client_->UavTrack(uav_, "uav");
  const int kFrames = frames;
  int seen = 0, gap = 0, longest_gap = 0;
  double offset_sum = 0, worst_offset = 0;
  for (int i = 0; i < kFrames; ++i) {
    const proto::Frame& frame = client_->StepAndReceive();
    const proto::Box* car = BoxOf(frame, car_);
    if (!car || car->visibility() <= 0.f) {
      longest_gap = std::max(longest_gap, ++gap);
      continue;
    }
    gap = 0;
    ++seen;
    const double offset = std::hypot(car->x() + 0.5 * car->width() - 160.0, car->y() + 0.5 * car->height() - 90.0);
    offset_sum += offset;
    worst_offset = std::max(worst_offset, offset);
    client_->SendTrackerOutput(frame.frame_id(), car->x(), car->y(), car->width(), car->height(), 1.f);
  }
  std::printf("servo: car seen in %d of %d frames, longest gap %d, centre offset mean %.1f px, worst %.1f px\n", seen,
              kFrames, longest_gap, offset_sum / std::max(seen, 1), worst_offset);
  EXPECT_GE(seen, kFrames * 95 / 100);
  EXPECT_LT(longest_gap, 30) << "frames in a row without the car";
  EXPECT_LT(offset_sum / std::max(seen, 1), max_mean_offset);
  const proto::State state = client_->GetState();
  EXPECT_LT(Distance(state, car_, uav_), 60.0);
}

TEST_F(TrackingServoTest, TheGroundTruthTrackerKeepsTheCarInView) { FlyWithGroundTruth(900, 10.0); }

// The paper's hardest case: the hard tracking map at 8 m/s, a whole lap.
TEST_F(TrackingServoTest, TheGroundTruthTrackerFollowsAt8MetresPerSecondOnTheHardMap) {
  Start({"--map", SourcePath("scenes/tracking/hard_urban.map"), "--car-speed", "8"});
  FlyWithGroundTruth(3000, 30.0);
}

TEST_F(TrackingServoTest, WithoutBoxesTheUavHoldsStill) {
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  client_->StepAndReceive();
  client_->UavTrack(uav_, "uav");
  const auto position = [&] {
    const proto::State state = client_->GetState();
    for (const auto& e : state.entities()) {
      if (e.id() == uav_) return e.position();
    }
    return proto::Vec3();
  };
  for (int i = 0; i < 30; ++i) client_->StepAndReceive();  // settle
  const proto::Vec3 before = position();
  for (int i = 0; i < 90; ++i) client_->StepAndReceive();
  const proto::Vec3 after = position();
  EXPECT_LT(std::hypot(after.x() - before.x(), after.y() - before.y()), 0.5);
}

// A box sent by a tracker of another UAV's camera does not steer this one.
TEST_F(TrackingServoTest, BoxesOfAnotherUavsCameraDoNotSteerIt) {
  const uint32_t other = client_->Spawn(proto::ENTITY_KIND_UAV, "other", 30, 30, 15);
  client_->AddCamera({.name = "other_cam", .mounted_on = "other", .pitch_down_deg = 60, .gimbal = true});
  client_->UavTrack(other, "other_cam");
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  const auto other_position = [&] {
    const proto::State state = client_->GetState();
    for (const auto& e : state.entities()) {
      if (e.id() == other) return e.position();
    }
    return proto::Vec3();
  };
  for (int i = 0; i < 30; ++i) client_->StepAndReceive();
  const proto::Vec3 before = other_position();
  for (int i = 0; i < 60; ++i) {
    const proto::Frame& frame = client_->StepAndReceive();
    // A box far to the left of the uav camera's image: would turn a UAV it steered.
    client_->SendTrackerOutput(frame.frame_id(), 0, 0, 20, 20, 1.f);
  }
  const proto::Vec3 after = other_position();
  EXPECT_LT(std::hypot(after.x() - before.x(), after.y() - before.y()), 0.5);
}

TEST_F(TrackingServoTest, ACameraOnAnotherEntityIsRefusedNamingTheUavsCameras) {
  try {
    client_->UavTrack(uav_, "car_chase");
    FAIL() << "a camera not on the UAV was accepted";
  } catch (const ServerError& e) {
    EXPECT_EQ(e.code(), proto::ERROR_CODE_INVALID_ARGUMENT);
    EXPECT_NE(std::string(e.what()).find("is not a camera mounted on 'uav'; its cameras steer it: 'uav'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace sim4cv::testing
