// A World and its graphics with a map's traffic (docs/maps.md, "Traffic"):
// the cars the World drives keep clear of traffic cars and walkers, two runs
// are bit-identical, a warm step and a warm graphics update allocate
// nothing, and every traffic object is labelled with its class and a unique
// id after the map's own objects.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>

#include "server/render/scene_graphics.h"
#include "server/sim/traffic/footprint.h"
#include "server/sim/world.h"
#include "sim4cv.pb.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/traffic_test_support.h"

namespace sim4cv::sim {
namespace {

constexpr double kDt = 1.0 / 240.0;

// Distance between two rectangles that do not overlap (0 if they do): the
// closest pair of points always has a corner of one of them.
double BoxGap(const traffic::Box2& a, const traffic::Box2& b) {
  if (traffic::Overlap(a, b)) return 0.0;
  double gap = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector2d& corner : traffic::Corners(a)) gap = std::min(gap, traffic::DistanceTo(b, corner));
  for (const Eigen::Vector2d& corner : traffic::Corners(b)) gap = std::min(gap, traffic::DistanceTo(a, corner));
  return gap;
}

Scene TrafficScene(const char* map, int cars, int parked, int walkers) {
  Scene scene = SceneFromMap((traffic::testing::SourceDir() / map).string(), "", 6.0f, 320, 180);
  traffic::TrafficConfig config;
  config.moving_cars = cars;
  config.parked_cars = parked;
  config.pedestrians = walkers;
  AddTraffic(scene, config);
  return scene;
}

class TargetInTraffic : public ::testing::TestWithParam<const char*> {};

// hard_urban has crosswalks on its straights; train/01_urban has junctions
// with lights, which the target car does not obey (it is driven, not a
// traffic participant): traffic and walkers give way to it.
INSTANTIATE_TEST_SUITE_P(Maps, TargetInTraffic,
                         ::testing::Values("scenes/tracking/hard_urban.map", "scenes/driving/train/01_urban.map"));

TEST_P(TargetInTraffic, TheTargetCarKeepsClearOfTrafficAndWalkers) {
  const Scene scene = TrafficScene(GetParam(), 12, 0, 20);
  World world(scene);
  State state = world.InitialState();
  ASSERT_EQ(state.traffic.cars.size(), 12u);
  ASSERT_EQ(state.traffic.walkers.size(), 20u);
  double nearest_car = std::numeric_limits<double>::infinity();
  double nearest_walker = nearest_car;
  const Eigen::Vector3d start = state.Find(kCarEntityId)->body.position;
  double travelled = 0, stopped_for = 0, longest_stop = 0;
  Eigen::Vector3d last = start;
  for (int step = 0; step < 90 * 240; ++step) {
    world.Step(state, kDt);
    const Eigen::Vector2d target = state.Find(kCarEntityId)->body.position.head<2>();
    const BodyState& body = state.Find(kCarEntityId)->body;
    const traffic::Box2 target_box{target, body.Yaw(), traffic::kCarLength / 2, traffic::kCarWidth / 2};
    for (const auto& car : state.traffic.cars) {
      const traffic::Box2 other{car.position.head<2>(), car.heading, traffic::kCarLength / 2, traffic::kCarWidth / 2};
      nearest_car = std::min(nearest_car, BoxGap(target_box, other));
    }
    stopped_for = body.linear_velocity.norm() < 0.05 ? stopped_for + kDt : 0.0;
    longest_stop = std::max(longest_stop, stopped_for);
    for (const auto& walker : state.traffic.walkers) {
      nearest_walker = std::min(nearest_walker, traffic::DistanceTo(target_box, walker.position.head<2>()));
    }
    travelled += (state.Find(kCarEntityId)->body.position - last).norm();
    last = state.Find(kCarEntityId)->body.position;
  }
  // Body to body (4.5 x 1.8 m boxes): cars passing in opposite lanes are
  // 2.2 m apart; the car's body keeps 0.6 m off a walker's centre.
  EXPECT_GT(nearest_car, 0.5) << "a traffic car ran into the target or the target into it";
  EXPECT_GT(nearest_walker, 0.6) << "the target car brushed past or ran into a walker";
  EXPECT_GT(travelled, 120.0) << "the target still gets somewhere in 90 s";
  EXPECT_LT(longest_stop, 30.0) << "no deadlock between the target and traffic";
  std::printf(
      "target car in traffic for 90 s: %.0f m driven, longest stop %.1f s, nearest traffic car body %.2f m, "
      "nearest walker %.2f m from its body\n",
      travelled, longest_stop, nearest_car, nearest_walker);
}

TEST(WorldTrafficTest, TwoRunsWithTrafficAreBitIdentical) {
  const Scene scene = TrafficScene("scenes/driving/train/01_urban.map", 10, 5, 12);
  World a(scene), b(scene);
  State sa = a.InitialState(), sb = b.InitialState();
  for (int step = 0; step < 20 * 240; ++step) {
    a.Step(sa, kDt);
    b.Step(sb, kDt);
  }
  for (std::size_t i = 0; i < sa.traffic.cars.size(); ++i) {
    ASSERT_TRUE(sa.traffic.cars[i].position == sb.traffic.cars[i].position) << "car " << i;
  }
  for (std::size_t i = 0; i < sa.traffic.walkers.size(); ++i) {
    ASSERT_TRUE(sa.traffic.walkers[i].position == sb.traffic.walkers[i].position) << "walker " << i;
  }
  EXPECT_TRUE(sa.Find(kCarEntityId)->body.position == sb.Find(kCarEntityId)->body.position);
}

TEST(WorldTrafficTest, WarmStepsAndGraphicsUpdatesAllocateNothing) {
  const Scene scene = TrafficScene("scenes/driving/train/01_urban.map", 10, 5, 12);
  World world(scene);
  State state = world.InitialState();
  render::SceneGraphics graphics(scene);
  for (int step = 0; step < 240; ++step) world.Step(state, kDt);
  graphics.Update(state);
  EXPECT_EQ(sim4cv::testing::AllocationsIn([&] {
              for (int frame = 0; frame < 60; ++frame) {
                for (int step = 0; step < 8; ++step) world.Step(state, kDt);
                graphics.Update(state);
              }
            }),
            0u);
}

TEST(WorldTrafficTest, TrafficIsLabelledWithItsClassAfterTheMapsObjects) {
  const Scene scene = TrafficScene("scenes/driving/train/01_urban.map", 6, 4, 8);
  render::SceneGraphics graphics(scene);
  const World world(scene);
  graphics.Update(world.InitialState());
  std::multiset<uint32_t> classes;
  uint32_t previous = 0;
  for (const render::LabelledObject& object : graphics.labelled_objects()) {
    EXPECT_GT(object.instance, previous) << "ids ascend and are unique";
    previous = object.instance;
    EXPECT_LT(object.instance, graphics.instance_id_bound());
    classes.insert(object.object_class);
  }
  const std::size_t lights = scene.traffic->lights().size();
  EXPECT_GT(lights, 0u) << "hard_urban has junctions";
  EXPECT_EQ(classes.count(proto::OBJECT_CLASS_TRAFFIC_LIGHT), lights);
  EXPECT_EQ(classes.count(proto::OBJECT_CLASS_PEDESTRIAN), 8u);
  EXPECT_EQ(classes.count(proto::OBJECT_CLASS_CAR), 1u + 4u + 6u) << "the target, parked and moving cars";
  // The 3D ground truth lists the same moving objects: entities, then traffic.
  EXPECT_EQ(graphics.moving_objects().size(), 2u + 6u + 8u);
}

}  // namespace
}  // namespace sim4cv::sim
