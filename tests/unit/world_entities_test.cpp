// World's configuration between steps: spawning and removing cars and UAVs,
// routes and speeds, UAV orders (hold, velocity, follow), several UAVs at
// once, and replaying only some entities from a log while the rest is
// simulated. Tolerances are the ones docs/vehicles.md states.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "server/sim/controllers.h"
#include "server/sim/log/replay_track.h"
#include "server/sim/log/run_log_writer.h"
#include "server/sim/world.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::sim {
namespace {

UavOrder FollowOrder(uint32_t target) {
  UavOrder order;
  order.mode = UavOrder::Mode::kFollow;
  order.target = target;
  return order;
}

constexpr double kDt = 1.0 / 240.0;

void Simulate(World& world, State& state, double seconds) {
  for (int i = 0; i < static_cast<int>(std::lround(seconds / kDt)); ++i) world.Step(state, kDt);
}

std::string ErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "no error";
}

class WorldEntitiesTest : public ::testing::Test {
 protected:
  const Scene scene_ = DefaultScene(320, 180);
  World world_{scene_};
  State state_ = world_.InitialState();
};

TEST_F(WorldEntitiesTest, TheSceneHasItsCarAndItsCameraUav) {
  ASSERT_EQ(state_.entities.size(), 2u);
  EXPECT_EQ(state_.entities[0].id, kCarEntityId);
  EXPECT_EQ(state_.entities[0].kind, EntityKind::kCar);
  EXPECT_EQ(state_.entities[1].id, kUavEntityId);
  EXPECT_EQ(state_.entities[1].uav_order.mode, UavOrder::Mode::kFollow);
  EXPECT_EQ(state_.entities[1].uav_order.target, kCarEntityId);
}

TEST_F(WorldEntitiesTest, SpawnTakesTheLowestFreeIdAndAUniqueName) {
  const uint32_t a = world_.Spawn(state_, EntityKind::kUav, "", {{0, 0, 10}, 0});
  const uint32_t b = world_.Spawn(state_, EntityKind::kCar, "blue", {{20, 20, 0}, 0});
  EXPECT_EQ(a, 3u);
  EXPECT_EQ(b, 4u);
  EXPECT_EQ(state_.Find(a)->name, "uav_3");
  world_.Remove(state_, a);
  EXPECT_EQ(state_.Find(a), nullptr);
  EXPECT_EQ(world_.Spawn(state_, EntityKind::kUav, "", {{0, 0, 10}, 0}), 3u) << "the freed id is reused";
  EXPECT_NE(ErrorOf([&] {
              world_.Spawn(state_, EntityKind::kCar, "blue", {{0, 0, 0}, 0});
            }).find("an entity named 'blue' already exists"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              world_.Spawn(state_, EntityKind::kUav, "low", {{0, 0, 0.1}, 0});
            }).find("z is 0.1"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              world_.Spawn(state_, EntityKind::kCar, "", {{NAN, 0, 0}, 0});
            }).find("not finite"),
            std::string::npos);
  // Stepping with the new entities runs, and the parked car stays put.
  const Eigen::Vector3d parked = state_.Find(b)->body.position;
  Simulate(world_, state_, 2.0);
  EXPECT_LT((state_.Find(b)->body.position - parked).head<2>().norm(), 0.05);
}

TEST_F(WorldEntitiesTest, ErrorsNameTheIdAndTheKind) {
  EXPECT_NE(ErrorOf([&] { world_.Remove(state_, 42); }).find("no entity has id 42; the world holds 1 ('car', car), 2"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              world_.SetRoute(state_, kUavEntityId, {{0, 0}, {1, 1}}, false, 3);
            }).find("entity 2 ('uav') is a UAV, not a car"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              world_.SetRoute(state_, kCarEntityId, {{0, 0}, {1, 1}}, false, 99);
            }).find("speed 99"),
            std::string::npos);
  const uint32_t car = world_.Spawn(state_, EntityKind::kCar, "", {{30, -60, 0}, 0});
  EXPECT_NE(ErrorOf([&] { world_.SetCruiseSpeed(state_, car, 4); }).find("has no route"), std::string::npos);
  EXPECT_NE(ErrorOf([&] {
              world_.SetUavOrder(state_, kUavEntityId, FollowOrder(77));
            }).find("cannot follow entity 77"),
            std::string::npos);
}

TEST_F(WorldEntitiesTest, AUavHoldsAPointItIsSentTo) {
  // In the open between the buildings and the road (the default scene's map: docs/scenes.md).
  const uint32_t uav = world_.Spawn(state_, EntityKind::kUav, "scout", {{0, -20, 10}, 0});
  UavOrder hold;
  hold.mode = UavOrder::Mode::kHold;
  hold.position = {6, -24, 14};
  hold.yaw = 1.0;
  world_.SetUavOrder(state_, uav, hold);
  Simulate(world_, state_, 8.0);
  const BodyState& body = state_.Find(uav)->body;
  EXPECT_LT((body.position - hold.position).norm(), 0.1) << body.position.transpose();
  EXPECT_NEAR(WrapAngle(body.Yaw() - 1.0), 0.0, 0.02);
}

TEST_F(WorldEntitiesTest, AUavFliesAVelocityItIsGiven) {
  const uint32_t uav = world_.Spawn(state_, EntityKind::kUav, "", {{0, -20, 10}, 0});
  UavOrder fly;
  fly.mode = UavOrder::Mode::kVelocity;
  fly.velocity = {2, 1, 0};
  world_.SetUavOrder(state_, uav, fly);
  Simulate(world_, state_, 6.0);
  const BodyState& body = state_.Find(uav)->body;
  EXPECT_LT((body.linear_velocity - fly.velocity).norm(), 0.1) << body.linear_velocity.transpose();
  EXPECT_NEAR(body.position.z(), 10.0, 0.3);
}

TEST_F(WorldEntitiesTest, FourUavsFilmTheCarEachFromItsOwnStation) {
  std::vector<uint32_t> uavs = {kUavEntityId};
  for (int i = 1; i < 4; ++i) {
    const BodyState& camera = state_.Find(kUavEntityId)->body;
    uavs.push_back(world_.Spawn(state_, EntityKind::kUav, "", {camera.position + Eigen::Vector3d(0, 0, 3.0 * i), 0}));
    UavOrder follow = state_.Find(kUavEntityId)->uav_order;
    follow.altitude += 3.0 * i;
    world_.SetUavOrder(state_, uavs.back(), follow);
  }
  double worst = 0;
  for (int second = 0; second < 20; ++second) {
    Simulate(world_, state_, 1.0);
    if (second < 3) continue;  // the car is still accelerating from rest
    for (const uint32_t id : uavs) {
      const Entity& uav = *state_.Find(id);
      const UavSetpoint station = FollowTarget(uav.uav_order, state_.Find(kCarEntityId)->body);
      worst = std::max(worst, (uav.body.position - station.position).norm());
    }
  }
  EXPECT_LT(worst, 1.5) << "every UAV keeps within 1.5 m of its station while the car laps";
}

TEST_F(WorldEntitiesTest, RemovingAFollowedCarMakesItsUavHold) {
  const uint32_t car = world_.Spawn(state_, EntityKind::kCar, "", {{30, -60, 0}, 0});
  world_.SetUavOrder(state_, kUavEntityId, FollowOrder(car));
  Simulate(world_, state_, 1.0);
  world_.Remove(state_, car);
  const Entity& uav = *state_.Find(kUavEntityId);
  EXPECT_EQ(uav.uav_order.mode, UavOrder::Mode::kHold);
  const Eigen::Vector3d held = uav.uav_order.position;
  Simulate(world_, state_, 3.0);
  EXPECT_LT((state_.Find(kUavEntityId)->body.position - held).norm(), 0.5);
}

TEST_F(WorldEntitiesTest, ASpawnedCarDrivesTheRouteItIsGivenAndStopsAtItsEnd) {
  const uint32_t car = world_.Spawn(state_, EntityKind::kCar, "", {{-40, -44, 0}, 0});
  world_.SetRoute(state_, car, {{-40, -44}, {20, -44}}, false, 5.0f);
  Simulate(world_, state_, 6.0);
  EXPECT_GT(state_.Find(car)->body.linear_velocity.x(), 3.0);
  Simulate(world_, state_, 14.0);
  const BodyState& body = state_.Find(car)->body;
  EXPECT_NEAR(body.position.x(), 20.0, 1.5) << "it stopped at the end of its path";
  EXPECT_LT(body.linear_velocity.norm(), 0.2);
}

TEST_F(WorldEntitiesTest, ReplayingOnlyTheTargetLetsTheUavFlyByPhysics) {
  const std::string path = ::testing::TempDir() + "world_replay_only_test.s4log";
  std::vector<State> recorded;
  {
    World world(scene_);
    State state = world.InitialState();
    runlog::RunLogWriter writer(path, {});
    runlog::FrameLogRecord record;
    for (uint64_t frame = 1; frame <= 60; ++frame) {
      Simulate(world, state, 8 * kDt);
      state.frame_id = frame;
      recorded.push_back(state);
      record.Clear();
      record.frame_id = frame;
      for (const Entity& entity : state.entities) record.entities.push_back({entity.id, entity.body});
      writer.Append(record);
    }
  }
  world_.SetReplay(std::make_shared<const runlog::ReplayTrack>(runlog::ReplayTrack::Load(path)), {kCarEntityId});
  UavOrder hold;
  hold.mode = UavOrder::Mode::kHold;
  hold.position = state_.Find(kUavEntityId)->body.position + Eigen::Vector3d(0, 0, 5);
  world_.SetUavOrder(state_, kUavEntityId, hold);
  for (uint64_t frame = 1; frame <= 60; ++frame) {
    Simulate(world_, state_, 8 * kDt);
    state_.frame_id = frame;
    const BodyState& car = state_.Find(kCarEntityId)->body;
    ASSERT_TRUE(car.position == recorded[frame - 1].Find(kCarEntityId)->body.position) << "frame " << frame;
  }
  // The UAV climbed to its hold point instead of following its logged path.
  EXPECT_LT((state_.Find(kUavEntityId)->body.position - hold.position).norm(), 0.5);
  EXPECT_GT((state_.Find(kUavEntityId)->body.position - recorded.back().Find(kUavEntityId)->body.position).norm(), 3.0);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace sim4cv::sim

namespace sim4cv::sim {
namespace {

TEST_F(WorldEntitiesTest, APedestrianWalksItsRouteAndStandsAtItsEnd) {
  const uint32_t walker = world_.Spawn(state_, EntityKind::kPedestrian, "", {{0, -20, 5}, 0});
  EXPECT_EQ(state_.Find(walker)->name, "pedestrian_3");
  EXPECT_EQ(state_.Find(walker)->body.position, Eigen::Vector3d(0, -20, 0)) << "on the ground, whatever z was";
  Simulate(world_, state_, 1.0);
  EXPECT_EQ(state_.Find(walker)->body.position, Eigen::Vector3d(0, -20, 0)) << "it stands until it has a route";
  world_.SetRoute(state_, walker, {{0, -20}, {10, -20}, {10, -10}}, false, 1.25f);
  Simulate(world_, state_, 4.0);
  const BodyState& body = state_.Find(walker)->body;
  EXPECT_NEAR(body.position.x(), 5.0, 0.02) << "4 s at 1.25 m/s along the first leg";
  EXPECT_NEAR(body.Yaw(), 0.0, 1e-6);
  EXPECT_NEAR(body.linear_velocity.x(), 1.25, 1e-9);
  Simulate(world_, state_, 20.0);
  EXPECT_LT((state_.Find(walker)->body.position - Eigen::Vector3d(10, -10, 0)).norm(), 1e-6) << "and stands at its end";
  EXPECT_TRUE(state_.Find(walker)->body.linear_velocity.isZero());
  EXPECT_NE(ErrorOf([&] {
              world_.SetRoute(state_, walker, {{0, 0}, {1, 0}}, false, 12.0f);
            }).find("walking speed 12"),
            std::string::npos);
}

}  // namespace
}  // namespace sim4cv::sim

namespace sim4cv::sim {
namespace {

// The scene's car (driving east along y = -42 from x = -40 at the start)
// meets a pedestrian standing in its lane, then a parked spawned car: it
// stops short of each, and drives on once the way is clear.
TEST_F(WorldEntitiesTest, TheCarStopsForAPedestrianAndACarInItsLane) {
  const Eigen::Vector2d start = state_.Find(kCarEntityId)->body.position.head<2>();
  const uint32_t walker = world_.Spawn(state_, EntityKind::kPedestrian, "", {{start.x() + 30, start.y(), 0}, 0});
  Simulate(world_, state_, 15.0);
  const BodyState& car = state_.Find(kCarEntityId)->body;
  const double to_walker = (state_.Find(walker)->body.position - car.position).head<2>().norm();
  EXPECT_GT(to_walker, 3.0) << "stopped short of the pedestrian";
  EXPECT_LT(to_walker, 6.0) << "but not far short";
  EXPECT_LT(car.linear_velocity.norm(), 0.1);
  world_.Remove(state_, walker);
  const uint32_t parked = world_.Spawn(state_, EntityKind::kCar, "", {{start.x() + 55, start.y(), 0}, 0});
  Simulate(world_, state_, 15.0);
  const double to_parked =
      (state_.Find(parked)->body.position - state_.Find(kCarEntityId)->body.position).head<2>().norm();
  EXPECT_GT(to_parked, 5.0) << "stopped behind the car, bodies apart";
  EXPECT_LT(to_parked, 8.0);
}

}  // namespace
}  // namespace sim4cv::sim
