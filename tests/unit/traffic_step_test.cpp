// Moving cars and walkers over time: they stay on their lanes and paths,
// keep their gaps, obey the lights, and every run is bit-identical.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstring>
#include <iostream>
#include <limits>
#include <numbers>
#include <vector>

#include "server/sim/map/lane_curve.h"
#include "server/sim/traffic/footprint.h"
#include "server/sim/traffic/traffic_state.h"
#include "tests/support/allocation_counter.h"
#include "tests/unit/traffic_test_support.h"

namespace sim4cv::traffic {
namespace {

using testing::Config;
using testing::GridMap;
using testing::LoadShipped;
using testing::TrafficWorld;

constexpr double kDt = 1.0 / 60;
constexpr int kTwoMinutes = 120 * 60;

Box2 BodyOf(const MovingCar& car) { return {car.position.head<2>(), car.heading, kCarLength / 2, kCarWidth / 2}; }

// Whether b drives in a's lane near a: the same way, and beside a's centre
// line by less than a lane.
bool SameLane(const MovingCar& a, const MovingCar& b) {
  if (std::abs(map::WrapAngle(a.heading - b.heading)) > std::numbers::pi / 4) return false;
  const Eigen::Vector2d d = b.position.head<2>() - a.position.head<2>();
  const double lateral = -std::sin(a.heading) * d.x() + std::cos(a.heading) * d.y();
  return std::abs(lateral) < map::kLaneWidth / 2;
}

struct FleetRun {
  double min_same_lane = std::numeric_limits<double>::infinity();  // centre to centre, m
  double min_any = std::numeric_limits<double>::infinity();
  int overlaps = 0;                                                 // steps x pairs whose bodies touched
  double closest_walker = std::numeric_limits<double>::infinity();  // a walker's centre to a car's body
  int junction_entries = 0;                                         // lit junctions entered
  int entries_on_red = 0;
  int red_waits = 0;          // times a car came to rest before a red light
  int worst_off_lane_um = 0;  // micrometres from the nearest lane centre, sampled each second
  double mean_speed = 0;
};

FleetRun RunFleet(const TrafficWorld& world, int steps) {
  TrafficState state = InitialTraffic(world.plan);
  FleetRun run;
  double speed_sum = 0;
  std::vector<bool> waiting(state.cars.size(), false);
  for (int step = 0; step < steps; ++step) {
    const double t = step * kDt;
    std::vector<map::SegmentId> before;
    for (const MovingCar& car : state.cars) before.push_back(car.route[0]);
    StepTraffic(world.plan, state, t, kDt, {});
    for (std::size_t i = 0; i < state.cars.size(); ++i) {
      const MovingCar& car = state.cars[i];
      speed_sum += car.speed;
      const int light = world.plan.LightControlling(car.route[0]);
      if (car.route[0] != before[i] && light >= 0) {
        ++run.junction_entries;
        if (world.plan.SignalAt(light, t) == Signal::kRed) ++run.entries_on_red;
      }
      const int held_by = car.stopping_for >= 0 ? world.plan.LightControlling(car.stopping_for) : -1;
      const bool waits = held_by >= 0 && car.speed < 0.05 && world.plan.SignalAt(held_by, t) == Signal::kRed;
      if (waits && !waiting[i]) ++run.red_waits;
      waiting[i] = waits;
      if (step % 60 == 0) {
        const double off = world.graph.Nearest(car.position.head<2>(), car.heading).distance;
        run.worst_off_lane_um = std::max(run.worst_off_lane_um, static_cast<int>(std::ceil(off * 1e6)));
      }
      for (const Walker& w : state.walkers) {
        run.closest_walker = std::min(run.closest_walker, DistanceTo(BodyOf(car), w.position.head<2>()));
      }
      for (std::size_t j = i + 1; j < state.cars.size(); ++j) {
        const MovingCar& other = state.cars[j];
        const double distance = (car.position - other.position).norm();
        run.min_any = std::min(run.min_any, distance);
        if (SameLane(car, other) || SameLane(other, car)) run.min_same_lane = std::min(run.min_same_lane, distance);
        if (Overlap(BodyOf(car), BodyOf(other))) ++run.overlaps;
      }
    }
  }
  run.mean_speed = speed_sum / (static_cast<double>(steps) * state.cars.size());
  return run;
}

TEST(TrafficStepTest, FifteenCarsKeepTheirGapsAndTheLightsForTwoMinutes) {
  for (const char* path : {"scenes/driving/train/01_urban.map", "scenes/driving/test/01_desert.map"}) {
    SCOPED_TRACE(path);
    const TrafficWorld world(LoadShipped(path), Config(15, 0, 20));
    const FleetRun run = RunFleet(world, kTwoMinutes);
    std::cout << path << ": min same-lane gap " << run.min_same_lane << " m, min any pair " << run.min_any
              << " m, closest walker " << run.closest_walker << " m, junction entries " << run.junction_entries
              << " (on red " << run.entries_on_red << "), waits at red " << run.red_waits << ", mean speed "
              << run.mean_speed << " m/s, worst off-lane " << run.worst_off_lane_um << " um\n";
    EXPECT_GE(run.min_same_lane, 5.0);
    EXPECT_EQ(run.overlaps, 0);
    EXPECT_GE(run.closest_walker, kWalkerRadius);
    EXPECT_EQ(run.entries_on_red, 0);
    EXPECT_GT(run.junction_entries, 20);
    EXPECT_GT(run.red_waits, 5);
    EXPECT_LE(run.worst_off_lane_um, 1);
    EXPECT_GT(run.mean_speed, 2.0);  // traffic flows, no gridlock
  }
}

// The crossroads in the middle of the grid map, entered from the north: a
// car 20 m before it, on the straight south of the T-junction above.
struct Approach {
  map::SegmentId segment = -1;  // southbound on tile 2,1
  int light = -1;
  Eigen::Vector2d stop_line{0, 0};
};

Approach NorthApproach(const TrafficWorld& world) {
  Approach approach;
  approach.segment = *world.graph.Find({2, 1}, map::Edge::kNorth, map::Edge::kSouth);
  const map::SegmentId into = *world.graph.Find({2, 2}, map::Edge::kNorth, map::Edge::kSouth);
  approach.light = world.plan.LightControlling(into);
  const map::LanePoint entry = world.graph.At(into, 0);
  approach.stop_line = entry.position + Eigen::Vector2d(0, kStopLineBack);  // southbound: back is +y
  return approach;
}

// The first time after `from` at which `light` turns `signal`.
double NextChange(const TrafficPlan& plan, int light, Signal signal, double from) {
  double t = from;
  while (plan.SignalAt(light, t) == signal) t += 1e-3;
  while (plan.SignalAt(light, t) != signal) t += 1e-3;
  return t;
}

TEST(TrafficStepTest, ACarStopsBehindTheStopLineAtRedAndGoesOnGreen) {
  const TrafficWorld world(GridMap(), Config(0, 0, 0));
  const Approach approach = NorthApproach(world);
  ASSERT_GE(approach.light, 0);
  const double red = NextChange(world.plan, approach.light, Signal::kRed, 0.0);
  const double green = NextChange(world.plan, approach.light, Signal::kGreen, red);
  TrafficState state;
  state.cars.push_back(CarAt(world.plan, approach.segment, 0.0, 8.0, 1, 8.0));
  double closest = std::numeric_limits<double>::infinity();  // front bumper to stop line, while red
  double entered = -1;
  for (double t = red; t < green + 10; t += kDt) {
    StepTraffic(world.plan, state, t, kDt, {});
    const MovingCar& car = state.cars[0];
    const double front_y = car.position.y() - kCarLength / 2;
    if (world.plan.SignalAt(approach.light, t) == Signal::kRed)
      closest = std::min(closest, front_y - approach.stop_line.y());
    if (entered < 0 && world.plan.JunctionOf(car.route[0]) >= 0) entered = t;
    if (t < green && t > green - 1) {
      EXPECT_LT(car.speed, 0.05) << "waiting at " << t;
    }
  }
  std::cout << "red light: front stopped " << closest << " m before the stop line; entered " << entered - green
            << " s after green\n";
  EXPECT_GE(closest, 0.0);
  EXPECT_LT(closest, 1.0);  // queued at the line, not metres short of it
  EXPECT_GT(entered, green);
  EXPECT_LT(entered, green + 6);
}

TEST(TrafficStepTest, ACarTooCloseToStopAtYellowGoesThrough) {
  const TrafficWorld world(GridMap(), Config(0, 0, 0));
  const Approach approach = NorthApproach(world);
  const double yellow = NextChange(world.plan, approach.light, Signal::kYellow, 0.0);
  TrafficState state;
  // 8 m/s with 3 m left to the stop line would need 10.7 m/s^2: it goes on.
  const double s = world.graph.segment(approach.segment).length() - kStopLineBack - kCarLength / 2 - 3.0;
  state.cars.push_back(CarAt(world.plan, approach.segment, s, 8.0, 1, 8.0));
  double t = yellow;
  for (; t < yellow + 3 && world.plan.JunctionOf(state.cars[0].route[0]) < 0; t += kDt) {
    StepTraffic(world.plan, state, t, kDt, {});
  }
  EXPECT_EQ(world.plan.SignalAt(approach.light, t), Signal::kYellow) << "entered at " << t - yellow << " s";
}

TEST(TrafficStepTest, ObstaclesAheadInTheLaneStopACarOnesBesideItDoNot) {
  // Eastbound along the top row (y = 40 - 2), from tile 1,0 into the T-junction at 2,0.
  TrafficConfig no_lights = Config(0, 0, 0);
  no_lights.traffic_lights = false;
  const TrafficWorld quiet(GridMap(), no_lights);
  const map::SegmentId start = *quiet.graph.Find({1, 0}, map::Edge::kWest, map::Edge::kEast);
  const map::LanePoint from = quiet.graph.At(start, 0);
  const std::vector<Obstacle> in_lane = {{from.position + Eigen::Vector2d(25, 0)}};
  const std::vector<Obstacle> oncoming = {{from.position + Eigen::Vector2d(25, 4), std::numbers::pi}};
  for (const auto* obstacles : {&in_lane, &oncoming}) {
    TrafficState state;
    state.cars.push_back(CarAt(quiet.plan, start, 0.0, 8.0, 3, 6.0));
    double closest = std::numeric_limits<double>::infinity();
    for (int step = 0; step < 20 * 60; ++step) {
      StepTraffic(quiet.plan, state, step * kDt, kDt, *obstacles);
      closest = std::min(closest, (state.cars[0].position.head<2>() - obstacles->front().position).norm());
    }
    if (obstacles == &in_lane) {
      std::cout << "obstacle in lane: the car's centre stopped " << closest << " m from it\n";
      EXPECT_GE(closest, kCarLength + 1.0);
      EXPECT_LT(state.cars[0].speed, 0.01);
    } else {
      EXPECT_GT(state.cars[0].speed, 1.0);  // drove past
    }
  }
}

TEST(TrafficStepTest, CarsStayOnLaneCentresWithHeadingAndYawRateOfTheLane) {
  const TrafficWorld world(LoadShipped("scenes/tracking/easy_desert.map"), Config(6, 0, 0));
  TrafficState state = InitialTraffic(world.plan);
  for (int step = 0; step < 30 * 60; ++step) {
    StepTraffic(world.plan, state, step * kDt, kDt, {});
    for (const MovingCar& car : state.cars) {
      const map::LanePoint at = world.graph.At(car.lane.segment, car.lane.s);
      ASSERT_EQ(car.route[0], car.lane.segment);
      ASSERT_EQ(car.position.head<2>(), at.position);
      ASSERT_EQ(car.position.z(), 0.0);
      ASSERT_EQ(car.heading, at.heading);
      const double curvature = world.graph.segment(car.lane.segment).curve.CurvatureAt(car.lane.s);
      ASSERT_EQ(car.yaw_rate, curvature * car.speed);
      ASSERT_NEAR(car.linear_velocity.norm(), car.speed, 1e-12);
      ASSERT_GE(car.acceleration, -8.0 - 1e-9);
      ASSERT_LE(car.acceleration, 2.0 + 1e-9);
      // Bends are taken at most at sqrt(2 m/s^2 * radius).
      if (curvature != 0) {
        ASSERT_LE(car.speed * car.speed * std::abs(curvature), 2.0 + 0.05);
      }
    }
  }
  for (const MovingCar& car : state.cars) EXPECT_GT(car.speed, 3.0);
}

// Every field a step writes, as bits, so equal means bit-identical.
template <typename T>
void Mix(uint64_t& hash, const T& value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (unsigned char b : bytes) hash = (hash ^ b) * 0x100000001B3ull;
}

uint64_t HashOf(const TrafficState& state) {
  uint64_t hash = 0xCBF29CE484222325ull;
  for (const MovingCar& c : state.cars) {
    for (double v : {c.lane.s, c.speed, c.acceleration, c.position.x(), c.position.y(), c.heading, c.yaw_rate,
                     c.linear_velocity.x(), c.linear_velocity.y()}) {
      Mix(hash, v);
    }
    Mix(hash, c.route);
    Mix(hash, c.rng_state);
  }
  for (const Walker& w : state.walkers) {
    for (double v : {w.s, w.pause_left, w.position.x(), w.position.y(), w.heading, w.linear_velocity.x()}) Mix(hash, v);
    Mix(hash, w.direction);
    Mix(hash, w.rng_state);
  }
  return hash;
}

uint64_t RunHash(uint64_t seed, int steps) {
  const TrafficWorld world(LoadShipped("scenes/driving/val/01_urban.map"), Config(12, 10, 20, seed));
  TrafficState state = InitialTraffic(world.plan);
  const std::vector<Obstacle> obstacles = {{world.plan.car_starts().front().lane.position}};
  uint64_t hash = 0;
  for (int step = 0; step < steps; ++step) {
    StepTraffic(world.plan, state, step * kDt, kDt, obstacles);
    hash ^= HashOf(state) + static_cast<uint64_t>(step);
  }
  return hash;
}

TEST(TrafficStepTest, TwoRunsAreBitIdentical) {
  const uint64_t first = RunHash(5, 60 * 60);
  EXPECT_EQ(first, RunHash(5, 60 * 60));
  EXPECT_NE(first, RunHash(6, 60 * 60));
}

TEST(TrafficStepTest, StepAllocatesNothingOnceWarm) {
  const TrafficWorld world(LoadShipped("scenes/driving/train/01_urban.map"), Config(15, 10, 30));
  TrafficState state = InitialTraffic(world.plan);
  const std::vector<Obstacle> obstacles = {{Eigen::Vector2d(0, 0)}};
  StepTraffic(world.plan, state, 0.0, kDt, obstacles);
  int step = 1;
  const std::size_t allocations = sim4cv::testing::AllocationsIn([&] {
    for (; step < 600; ++step) StepTraffic(world.plan, state, step * kDt, kDt, obstacles);
  });
  EXPECT_EQ(allocations, 0u);
}

TEST(TrafficStepTest, WalkersStayOnTheirPathsTurnAroundAndCrossOnlyAtRed) {
  const TrafficWorld world(GridMap(), Config(4, 0, 24));
  TrafficState state = InitialTraffic(world.plan);
  std::vector<int> turns(state.walkers.size(), 0);
  std::vector<double> stood(state.walkers.size(), 0.0);
  double shortest_pause = std::numeric_limits<double>::infinity();
  int crossings_started = 0;
  for (int step = 0; step < kTwoMinutes; ++step) {
    const double t = step * kDt;
    const std::vector<Walker> before = state.walkers;
    StepTraffic(world.plan, state, t, kDt, {});
    for (std::size_t i = 0; i < state.walkers.size(); ++i) {
      const Walker& w = state.walkers[i];
      const TrafficPlan::WalkPath& path = world.plan.walk_paths()[w.path];
      ASSERT_GE(w.s, 0.0);
      ASSERT_LE(w.s, path.length);
      const Eigen::Vector2d unit = (path.end - path.start) / path.length;
      ASSERT_LT((w.position.head<2>() - (path.start + unit * w.s)).norm(), 1e-9);
      if (w.direction != before[i].direction) ++turns[i];
      const bool moving = w.linear_velocity.norm() > 0;
      if (moving) {
        ASSERT_NEAR(std::abs(map::WrapAngle(w.heading - std::atan2(unit.y(), unit.x()) -
                                            (w.direction < 0 ? std::numbers::pi : 0))),
                    0.0, 1e-9);
        ASSERT_GE(w.speed, kMinWalkSpeed);
        ASSERT_LE(w.speed, kMaxWalkSpeed);
      }
      if (moving && before[i].linear_velocity.norm() == 0) {
        ++crossings_started;
        if (turns[i] > 0) shortest_pause = std::min(shortest_pause, stood[i]);
        ASSERT_EQ(world.plan.SignalAt(path.light, t), Signal::kRed) << "walker " << i << " set off at " << t;
      }
      stood[i] = moving ? 0.0 : stood[i] + kDt;
    }
  }
  const int fewest = *std::min_element(turns.begin(), turns.end());
  std::cout << "walkers: " << crossings_started << " crossings started, each turned round at least " << fewest
            << " times, shortest stand " << shortest_pause << " s\n";
  EXPECT_GE(fewest, 3);
  EXPECT_GE(shortest_pause, kMinPause - kDt);
}

TEST(TrafficStepTest, WithoutJunctionsWalkersCrossStraightsPausingAtTheEnds) {
  // Alone, walkers pause 1-3 s at each end; among cars, they also wait for a gap.
  for (int cars : {0, 8}) {
    const TrafficWorld world(LoadShipped("scenes/tracking/hard_urban.map"), Config(cars, 0, 12));
    TrafficState state = InitialTraffic(world.plan);
    std::vector<int> turns(state.walkers.size(), 0);
    std::vector<double> stood(state.walkers.size(), 0.0);
    double shortest = std::numeric_limits<double>::infinity(), longest = 0;
    double closest = std::numeric_limits<double>::infinity();  // walker's centre to a car's body
    for (int step = 0; step < 2 * 60 * 60; ++step) {
      const std::vector<Walker> before = state.walkers;
      StepTraffic(world.plan, state, step * kDt, kDt, {});
      for (std::size_t i = 0; i < state.walkers.size(); ++i) {
        const Walker& w = state.walkers[i];
        EXPECT_EQ(world.plan.walk_paths()[w.path].light, -1);
        if (w.direction != before[i].direction && w.pause_left > 0) {
          ++turns[i];
          EXPECT_GE(w.pause_left, kMinPause);
          EXPECT_LE(w.pause_left, kMaxPause);
        }
        const bool moving = w.linear_velocity.norm() > 0;
        if (moving && before[i].linear_velocity.norm() == 0 && turns[i] > 0) {
          shortest = std::min(shortest, stood[i]);
          longest = std::max(longest, stood[i]);
        }
        stood[i] = moving ? 0.0 : stood[i] + kDt;
        for (const MovingCar& car : state.cars)
          closest = std::min(closest, DistanceTo(BodyOf(car), w.position.head<2>()));
      }
    }
    std::cout << "walkers without lights among " << cars << " cars: each crossed at least "
              << *std::min_element(turns.begin(), turns.end()) << " times in two minutes, stood " << shortest << " to "
              << longest << " s at the kerb; closest to a car body " << closest << " m\n";
    EXPECT_GE(*std::min_element(turns.begin(), turns.end()), cars == 0 ? 8 : 4);
    EXPECT_GE(shortest, kMinPause - kDt);
    if (cars == 0) {
      EXPECT_LE(longest, kMaxPause + kDt);
    }
    EXPECT_GE(closest, kWalkerRadius);  // never touching
  }
}

TEST(TrafficStepTest, BadStepsAndCarsAreRefused) {
  const TrafficWorld world(GridMap(), Config(1, 0, 0));
  TrafficState state = InitialTraffic(world.plan);
  try {
    StepTraffic(world.plan, state, 0.0, -0.5, {});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("-0.5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(CarAt(world.plan, 0, 0.0, 0.0, 1), std::invalid_argument);
  EXPECT_THROW(CarAt(world.plan, 0, 0.0, 6.0, 1, -1.0), std::invalid_argument);
  EXPECT_THROW(CarAt(world.plan, 100000, 0.0, 6.0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace sim4cv::traffic
