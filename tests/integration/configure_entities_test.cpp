// Configure against the real daemon: spawning and removing entities, UAV
// orders, Reset, and Controls for ids that are not cars (default scene: car
// 1 drives the road loop, UAV 2 films it).
#include <cmath>
#include <limits>
#include <numbers>

#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

constexpr uint32_t kCarId = 1;
constexpr uint32_t kUavId = 2;

// Heading of an entity's body x axis, degrees counter-clockwise from east.
double YawDeg(const proto::EntityState& entity) {
  const auto& q = entity.orientation();
  return std::atan2(2 * (q.w() * q.z() + q.x() * q.y()), 1 - 2 * (q.y() * q.y() + q.z() * q.z())) * 180 /
         std::numbers::pi;
}

class EntitiesTest : public ConfigureTest {
 protected:
  void SetUp() override {
    StartDaemon();
    client_ = Connect("configure");
    client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  }

  // The entity's state after `frames` more frames; fails the test if it is gone.
  proto::EntityState After(int frames, uint32_t id) {
    const proto::Frame& frame = StepFrames(*client_, frames);
    const proto::EntityState* entity = FindEntity(frame.state(), id);
    EXPECT_NE(entity, nullptr) << "entity " << id << " is not in frame " << frame.frame_id();
    return entity ? *entity : proto::EntityState{};
  }

  std::unique_ptr<Client> client_;
};

TEST_F(EntitiesTest, SpawnedEntitiesAppearInTheWorldAndTheStateUntilRemoved) {
  const uint32_t uav = client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -10, -20, 20, 45);
  const uint32_t car = client_->Spawn(proto::ENTITY_KIND_CAR, "car_b", 0, -25, 0, 90);
  EXPECT_EQ(uav, 3u);
  EXPECT_EQ(car, 4u);

  const proto::WorldInfo world = client_->GetWorld();
  ASSERT_EQ(world.entities_size(), 4) << world.ShortDebugString();
  ASSERT_NE(FindEntity(world, "uav_b"), nullptr);
  ASSERT_NE(FindEntity(world, "car_b"), nullptr);
  EXPECT_EQ(FindEntity(world, "uav_b")->id(), uav);
  EXPECT_EQ(FindEntity(world, "uav_b")->kind(), proto::ENTITY_KIND_UAV);
  EXPECT_EQ(FindEntity(world, "car_b")->kind(), proto::ENTITY_KIND_CAR);
  // A new connection's Welcome lists them too.
  EXPECT_EQ(Connect("late")->welcome().entities_size(), 4);

  // In the frames' State: the UAV hovers where it appeared, the car stands.
  const proto::EntityState uav_state = After(30, uav);
  EXPECT_EQ(uav_state.name(), "uav_b");
  EXPECT_LT(Distance(uav_state.position(), Vec(-10, -20, 20)), 0.5) << uav_state.ShortDebugString();
  EXPECT_NEAR(YawDeg(uav_state), 45, 2);
  const proto::EntityState car_state = After(1, car);
  EXPECT_EQ(car_state.name(), "car_b");
  EXPECT_NEAR(car_state.position().x(), 0, 0.2);
  EXPECT_NEAR(car_state.position().y(), -25, 0.2);
  EXPECT_NEAR(YawDeg(car_state), 90, 2);
  EXPECT_LT(std::hypot(car_state.linear_velocity().x(), car_state.linear_velocity().y()), 0.1) << "parked, brake on";

  // Names are unique; unknown ids are named.
  ExpectRefused([&] { client_->Spawn(proto::ENTITY_KIND_CAR, "uav_b", 5, -25, 0); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"'uav_b'", "already exists"});
  ExpectRefused([&] { client_->Remove(99); }, proto::ERROR_CODE_UNKNOWN_ENTITY, {"99", "'car_b'"});

  EXPECT_EQ(client_->Remove(uav).entities_size(), 3);
  const proto::Frame& frame = StepFrames(*client_, 1);
  EXPECT_EQ(FindEntity(frame.state(), uav), nullptr) << frame.state().ShortDebugString();
  EXPECT_NE(FindEntity(frame.state(), car), nullptr);
  EXPECT_FALSE(BoxOf(frame, uav).has_value());

  // The lowest free id is reused; an empty name becomes "uav_<id>".
  EXPECT_EQ(client_->Spawn(proto::ENTITY_KIND_UAV, "", 30, -20, 10), uav);
  EXPECT_NE(FindEntity(client_->GetWorld(), "uav_3"), nullptr);
  client_->Remove(uav);
  const proto::WorldInfo after = client_->Remove(car);
  EXPECT_EQ(after.entities_size(), 2);
  EXPECT_EQ(StepFrames(*client_, 1).state().entities_size(), 2);
}

TEST_F(EntitiesTest, UavHoldsACommandedPosition) {
  const uint32_t uav = client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -10, -20, 20);
  client_->UavHold(uav, -4, -24, 15, 90);
  const proto::EntityState held = After(240, uav);  // 8 s
  EXPECT_LT(Distance(held.position(), Vec(-4, -24, 15)), 0.5) << held.ShortDebugString();
  EXPECT_NEAR(YawDeg(held), 90, 3);
  EXPECT_LT(std::hypot(held.linear_velocity().x(), held.linear_velocity().y()), 0.3) << "it settled";
}

TEST_F(EntitiesTest, UavFliesACommandedVelocity) {
  const uint32_t uav = client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -10, -20, 20);
  const proto::EntityState start = After(1, uav);
  client_->UavVelocity(uav, 2, 0, 0);
  const proto::EntityState moved = After(90, uav);  // 3 s
  EXPECT_GT(moved.position().x() - start.position().x(), 3.0) << moved.ShortDebugString();
  EXPECT_NEAR(moved.position().y(), start.position().y(), 0.5);
  EXPECT_NEAR(moved.position().z(), start.position().z(), 0.5);
  EXPECT_NEAR(moved.linear_velocity().x(), 2.0, 0.3);
}

TEST_F(EntitiesTest, UavFollowsASpawnedCar) {
  // A second car drives west along the north side's right lane; a new UAV
  // films it with a camera of its own.
  const uint32_t car = client_->Spawn(proto::ENTITY_KIND_CAR, "car_b", 10, 42, 0, 180);
  client_->SetWaypoints(car, {{10, 42}, {-40, 42}}, /*closed=*/false, 4);
  const uint32_t uav = client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", 10, 30, 20);
  client_->UavFollow(uav, car);
  client_->AddCamera({.name = "uav_b_cam", .mounted_on = "uav_b", .width = 160, .height = 120, .pitch_down_deg = 60,
                      .gimbal = true, .z = -0.3});
  client_->Subscribe("uav_b_cam", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);

  const proto::Frame& frame = StepFrames(*client_, 180);  // 6 s
  const proto::EntityState& car_state = *FindEntity(frame.state(), car);
  const proto::EntityState& uav_state = *FindEntity(frame.state(), uav);
  EXPECT_LT(car_state.position().x(), 0) << "the car drove west: " << car_state.ShortDebugString();
  // Station: 15 m above the car, 15 / tan(60 deg) = 8.7 m behind it (east).
  EXPECT_NEAR(uav_state.position().z() - car_state.position().z(), 15, 1.5) << uav_state.ShortDebugString();
  EXPECT_NEAR(PlaneDistance(uav_state.position(), car_state.position()), 8.7, 2.0);
  EXPECT_GT(uav_state.position().x(), car_state.position().x());
  EXPECT_TRUE(BoxOf(frame, car).has_value()) << "the follower's camera sees the car: " << frame.ShortDebugString();

  // Unknown target: named.
  ExpectRefused([&] { client_->UavFollow(uav, 77); }, proto::ERROR_CODE_UNKNOWN_ENTITY, {"77"});
}

TEST_F(EntitiesTest, ResetBringsTheStartBack) {
  const proto::State initial = client_->GetState();
  ASSERT_EQ(initial.frame_id(), 0u);
  const proto::State first = StepFrames(*client_, 1).state();
  StepFrames(*client_, 20);
  client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -10, -20, 20);
  client_->SendControls(kCarId, 0.5f, 1.0f, 0.0f);
  StepFrames(*client_, 10);

  const proto::WorldInfo world = client_->Reset();
  EXPECT_EQ(world.frame_id(), 0u);
  EXPECT_EQ(world.entities_size(), 2);
  EXPECT_EQ(FindEntity(world, "uav_b"), nullptr);

  const proto::State reset = client_->GetState();
  EXPECT_EQ(reset.frame_id(), 0u);
  ASSERT_EQ(reset.entities_size(), 2);
  EXPECT_LT(Distance(reset.entities(0).position(), initial.entities(0).position()), 1e-6);
  // The subscription to the scene's camera stays; the run starts over, and
  // the car follows its lane again as in the first run.
  const proto::Frame& again = StepFrames(*client_, 1);
  EXPECT_EQ(again.frame_id(), 1u);
  ASSERT_EQ(again.state().entities_size(), 2);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT(Distance(again.state().entities(i).position(), first.entities(i).position()), 1e-6)
        << again.state().entities(i).ShortDebugString() << " vs " << first.entities(i).ShortDebugString();
  }
}

TEST_F(EntitiesTest, FramesArrivingWhileAConfigureWaitsAreKept) {
  auto other = Connect("other");
  other->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  client_->Step();
  other->Step();
  proto::Frame frame;
  // Once `other` has frame 1, it is on its way to client_ as well.
  ASSERT_TRUE(other->ReceiveFrame(frame, std::chrono::milliseconds(10000)));
  EXPECT_EQ(client_->Spawn(proto::ENTITY_KIND_UAV, "uav_b", -10, -20, 20), 3u);
  ASSERT_TRUE(client_->ReceiveFrame(frame, std::chrono::milliseconds(10000)));
  EXPECT_EQ(frame.frame_id(), 1u);
  EXPECT_EQ(frame.state().entities_size(), 2) << "rendered before the Spawn";
  other->Step();
  const proto::Frame& next = client_->StepAndReceive();
  EXPECT_EQ(next.frame_id(), 2u);
  EXPECT_EQ(next.state().entities_size(), 3) << "rendered after the Spawn";
}

TEST_F(EntitiesTest, ControlsForAnIdThatIsNotACarNameItAndTheWorld) {
  client_->SendControls(kUavId, 0.f, 0.5f, 0.f);
  proto::Error error = NextError(*client_, proto::ERROR_CODE_UNKNOWN_ENTITY);
  EXPECT_EQ(error.request_id(), 0u);
  for (const char* part : {"entity_id 2", "1 ('car'", "2 ('uav'"}) {
    EXPECT_NE(error.message().find(part), std::string::npos) << "'" << part << "' not in: " << error.message();
  }
  const uint32_t car = client_->Spawn(proto::ENTITY_KIND_CAR, "car_b", 0, -25, 0, 90);
  client_->SendControls(42, 0.f, 0.5f, 0.f);
  error = NextError(*client_, proto::ERROR_CODE_UNKNOWN_ENTITY);
  EXPECT_NE(error.message().find("entity_id 42"), std::string::npos) << error.message();
  EXPECT_NE(error.message().find("'car_b'"), std::string::npos) << error.message();

  // A spawned car takes Controls: full throttle moves it north.
  const double start_y = After(1, car).position().y();
  client_->SendControls(car, 0.f, 1.f, 0.f);
  EXPECT_GT(After(60, car).position().y() - start_y, 2.0);
  // Nothing else was refused meanwhile.
  EXPECT_EQ(client_->GetState().entities_size(), 3);
}

}  // namespace
}  // namespace sim4cv::testing

namespace sim4cv::testing {
namespace {

// A spawned pedestrian walks its waypoints on the pavement beside the road
// and shows up in the camera UAV's boxes, labelled as a pedestrian.
TEST_F(EntitiesTest, ASpawnedPedestrianWalksItsWaypointsAndIsLabelled) {
  const uint32_t walker = client_->Spawn(proto::ENTITY_KIND_PEDESTRIAN, "", -25, -47, 0);
  EXPECT_EQ(FindEntity(client_->GetWorld(), "pedestrian_3")->kind(), proto::ENTITY_KIND_PEDESTRIAN);
  client_->SetWaypoints(walker, {{-25, -47}, {40, -47}}, false, 1.5f);
  bool seen = false;
  proto::EntityState state;
  for (int frame = 0; frame < 90; ++frame) {
    const proto::Frame& f = StepFrames(*client_, 1);
    for (const proto::Box& box : f.boxes()) {
      if (box.object_id() == walker) {
        EXPECT_EQ(box.object_class(), proto::OBJECT_CLASS_PEDESTRIAN);
        seen = true;
      }
    }
    state = *FindEntity(f.state(), walker);
  }
  EXPECT_TRUE(seen) << "the UAV camera, filming the car as it passes, never saw the pedestrian";
  // 90 frames at 30 Hz: 3 s at 1.5 m/s.
  EXPECT_NEAR(state.position().x(), -25 + 4.5, 0.1);
  EXPECT_NEAR(state.position().y(), -47, 1e-6);
  EXPECT_NEAR(state.linear_velocity().x(), 1.5, 1e-6);
}

}  // namespace
}  // namespace sim4cv::testing
