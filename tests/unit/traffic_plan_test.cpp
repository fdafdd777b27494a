// The traffic plan: lights at every junction approach and off the lanes,
// their cycle, crosswalks, parked cars, where moving cars start, and the
// errors a config that cannot be met gets.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <string>

#include "server/sim/map/lane_curve.h"
#include "server/sim/traffic/footprint.h"
#include "tests/unit/traffic_test_support.h"

namespace sim4cv::traffic {
namespace {

using map::Edge;
using testing::Config;
using testing::GridMap;
using testing::LoadShipped;
using testing::TrafficWorld;

bool IsJunction(map::TileKind kind) { return kind == map::TileKind::kTJunction || kind == map::TileKind::kCrossroads; }

void ExpectLightsAtEveryApproach(const TrafficWorld& world) {
  const TrafficPlan& plan = world.plan;
  int approaches = 0;
  double nearest_lane = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < world.map.road.size(); ++i) {
    const map::TileCoord tile = world.map.CoordOf(i);
    if (!IsJunction(world.map.KindAt(tile))) continue;
    for (Edge entry : map::kEdges) {
      if (!map::Has(world.map.road[i], entry)) continue;
      ++approaches;
      int found = -1, count = 0;
      for (std::size_t l = 0; l < plan.lights().size(); ++l) {
        const TrafficPlan::Light& light = plan.lights()[l];
        if (plan.junctions()[light.junction].tile == tile && light.entry == entry) {
          found = static_cast<int>(l);
          ++count;
        }
      }
      ASSERT_EQ(count, 1) << "tile " << tile.col << "," << tile.row << " entry " << static_cast<int>(entry);
      const TrafficPlan::Light& light = plan.lights()[found];
      // Beside the arm, on the right of the traffic coming in, before the junction.
      const Eigen::Vector2d out = map::Outward(entry);
      const Eigen::Vector2d from_edge = light.position - (world.map.TileCentre(tile) + out * (world.map.tile_size / 2));
      const Eigen::Vector2d right(-out.y(), out.x());  // of traffic heading -out
      EXPECT_NEAR(from_edge.dot(right), kLightLateral, 1e-9);
      EXPECT_GE(from_edge.dot(out), 4.0);
      EXPECT_LE(from_edge.dot(out), 8.0 + 1e-9);
      EXPECT_NEAR(map::WrapAngle(light.heading - std::atan2(out.y(), out.x())), 0.0, 1e-12);  // facing the traffic
      EXPECT_EQ(light.axis, (entry == Edge::kNorth || entry == Edge::kSouth) ? 0 : 1);
      // Off the road: the road surface is within half a lane of a lane centre.
      const double off = world.graph.Nearest(light.position).distance;
      nearest_lane = std::min(nearest_lane, off);
      EXPECT_GE(off, map::kLaneWidth / 2 + 0.5);
      for (const map::MapObject& object : world.map.objects)
        EXPECT_GE(DistanceTo(FootprintOf(object), light.position), 0.3);
      // It holds exactly the junction's segments entering there.
      for (const map::LaneSegment& segment : world.graph.segments()) {
        const bool entering = segment.tile == tile && segment.entry == entry;
        EXPECT_EQ(plan.LightControlling(segment.id) == found, entering);
      }
      EXPECT_EQ(world.graph.segment(light.controls).tile, tile);
      EXPECT_EQ(world.graph.segment(light.controls).entry, entry);
    }
  }
  EXPECT_EQ(plan.lights().size(), static_cast<std::size_t>(approaches));
  std::cout << world.map.name << ": " << plan.junctions().size() << " junctions, " << approaches
            << " lights, nearest lane centre " << nearest_lane << " m\n";
}

TEST(TrafficPlanTest, LightsStandAtEveryJunctionApproachOffTheLanes) {
  const TrafficWorld grid(GridMap(), Config(0, 0, 0));
  EXPECT_EQ(grid.plan.junctions().size(), 5u);  // four T-junctions and a crossroads
  ExpectLightsAtEveryApproach(grid);
  ExpectLightsAtEveryApproach(TrafficWorld(LoadShipped("scenes/driving/train/01_urban.map"), Config(0, 0, 0)));
  ExpectLightsAtEveryApproach(TrafficWorld(LoadShipped("scenes/driving/test/01_urban.map"), Config(0, 0, 0)));
}

TEST(TrafficPlanTest, SignalsCycleAndTheTwoAxesOfAJunctionAreNeverOpenTogether) {
  TrafficConfig config = Config(0, 0, 0);
  config.green_s = 7;
  config.yellow_s = 2.5;
  config.all_red_s = 1.5;
  const TrafficWorld world(GridMap(), config);
  const TrafficPlan& plan = world.plan;
  EXPECT_DOUBLE_EQ(plan.cycle_s(), 22.0);
  constexpr double kTick = 1e-3;
  const int ticks = static_cast<int>(std::lround(2 * plan.cycle_s() / kTick));
  for (std::size_t j = 0; j < plan.junctions().size(); ++j) {
    double green[2] = {0, 0}, yellow[2] = {0, 0}, all_red = 0;
    for (int k = 0; k < ticks; ++k) {
      const double t = 100.0 + k * kTick;
      int seen[2] = {0, 0};
      Signal shown[2] = {Signal::kRed, Signal::kRed};
      for (std::size_t l = 0; l < plan.lights().size(); ++l) {
        if (plan.lights()[l].junction != static_cast<int>(j)) continue;
        const int axis = plan.lights()[l].axis;
        const TrafficPlan::SignalPhase phase = plan.PhaseAt(l, t);
        // The lights of one axis agree; the time left is when the signal really changes.
        if (seen[axis]++ > 0) {
          EXPECT_EQ(phase.signal, shown[axis]);
        }
        shown[axis] = phase.signal;
        if (phase.time_left > 2 * kTick) {
          EXPECT_EQ(plan.SignalAt(l, t + phase.time_left - kTick), phase.signal);
        }
        EXPECT_NE(plan.SignalAt(l, t + phase.time_left + kTick), phase.signal);
      }
      for (int axis : {0, 1}) {
        if (shown[axis] == Signal::kGreen) green[axis] += kTick;
        if (shown[axis] == Signal::kYellow) yellow[axis] += kTick;
      }
      ASSERT_FALSE(shown[0] != Signal::kRed && shown[1] != Signal::kRed) << "junction " << j << " at " << t;
      if (shown[0] == Signal::kRed && shown[1] == Signal::kRed) all_red += kTick;
    }
    // Two cycles: each axis twice green and twice yellow, and four all-red gaps.
    for (int axis : {0, 1}) {
      EXPECT_NEAR(green[axis], 2 * config.green_s, 2 * kTick);
      EXPECT_NEAR(yellow[axis], 2 * config.yellow_s, 2 * kTick);
    }
    EXPECT_NEAR(all_red, 4 * config.all_red_s, 4 * kTick);
  }
  // Junctions do not all switch together.
  bool differ = false;
  for (const TrafficPlan::Junction& junction : plan.junctions()) {
    EXPECT_GE(junction.phase_s, 0.0);
    EXPECT_LT(junction.phase_s, plan.cycle_s());
    differ = differ || junction.phase_s != plan.junctions().front().phase_s;
  }
  EXPECT_TRUE(differ);
}

TEST(TrafficPlanTest, ConflictsAreLanesThatCrossOrMerge) {
  const TrafficWorld world(GridMap(), Config(0, 0, 0));
  const auto id = [&](Edge entry, Edge exit) { return *world.graph.Find({2, 2}, entry, exit); };
  const map::SegmentId north_south = id(Edge::kNorth, Edge::kSouth);
  EXPECT_TRUE(world.plan.Conflict(north_south, id(Edge::kWest, Edge::kEast)));                      // crossing
  EXPECT_TRUE(world.plan.Conflict(id(Edge::kWest, Edge::kEast), north_south));                      // both ways
  EXPECT_TRUE(world.plan.Conflict(id(Edge::kNorth, Edge::kEast), id(Edge::kSouth, Edge::kNorth)));  // left across
  EXPECT_TRUE(world.plan.Conflict(id(Edge::kSouth, Edge::kEast), id(Edge::kWest, Edge::kEast)));    // merging
  EXPECT_FALSE(world.plan.Conflict(north_south, id(Edge::kSouth, Edge::kNorth)));                   // side by side
  EXPECT_FALSE(world.plan.Conflict(north_south, id(Edge::kNorth, Edge::kEast)));                    // one queue
  EXPECT_FALSE(world.plan.Conflict(id(Edge::kNorth, Edge::kWest), id(Edge::kSouth, Edge::kEast)));  // two right turns
  const map::SegmentId outside = *world.graph.Find({2, 1}, Edge::kNorth, Edge::kSouth);
  EXPECT_EQ(world.plan.JunctionOf(outside), -1);
  EXPECT_FALSE(world.plan.Conflict(outside, north_south));
}

TEST(TrafficPlanTest, CrosswalksCrossEveryArmOrWithoutJunctionsEveryStraight) {
  for (const auto& [path, junctions] : {std::pair{"grid", true}, std::pair{"scenes/tracking/hard_urban.map", false}}) {
    const TrafficWorld world(junctions ? GridMap() : LoadShipped(path), Config(0, 0, 0));
    int crosswalks = 0;
    for (std::size_t i = 0; i < world.map.road.size(); ++i) {
      const map::TileKind kind = world.map.KindAt(world.map.CoordOf(i));
      if (junctions && IsJunction(kind)) crosswalks += map::CountEdges(world.map.road[i]);
      if (!junctions && kind == map::TileKind::kStraight) ++crosswalks;
    }
    SCOPED_TRACE(path);
    EXPECT_EQ(world.plan.walk_paths().size(), static_cast<std::size_t>(crosswalks * kWalkLines));
    for (const TrafficPlan::WalkPath& walk : world.plan.walk_paths()) {
      // From pavement to pavement across both lanes.
      EXPECT_GE(world.graph.Nearest(walk.start).distance, map::kLaneWidth / 2 + 0.2 - 1e-9);
      EXPECT_GE(world.graph.Nearest(walk.end).distance, map::kLaneWidth / 2 + 0.2 - 1e-9);
      EXPECT_LE(world.graph.Nearest((walk.start + walk.end) / 2).distance, map::kLaneWidth / 2 + 1e-9);
      EXPECT_GE(walk.length, 2 * (map::kLaneWidth + 0.2) - 1e-9);
      EXPECT_LE(walk.length, 2 * kCrosswalkReach + 1e-9);
      EXPECT_EQ(walk.crossings.size(), 2u);  // the two lanes of a straight arm
      EXPECT_EQ(walk.light >= 0, junctions);
      for (const map::MapObject& object : world.map.objects) {
        EXPECT_GE(DistanceTo(FootprintOf(object), walk.start), kWalkerRadius);
        EXPECT_GE(DistanceTo(FootprintOf(object), walk.end), kWalkerRadius);
      }
    }
  }
}

TEST(TrafficPlanTest, ParkedCarsStandAtTheKerbOfStraightsClearOfLanesObjectsAndEachOther) {
  const TrafficWorld probe(LoadShipped("scenes/driving/train/01_urban.map"), Config(0, 0, 0));
  const int all = probe.plan.parked_car_capacity();
  const TrafficWorld world(LoadShipped("scenes/driving/train/01_urban.map"), Config(0, all, 0));
  const std::vector<Pose2>& parked = world.plan.parked_cars();
  ASSERT_EQ(parked.size(), static_cast<std::size_t>(all));
  ASSERT_GT(all, 50);
  double nearest_lane = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < parked.size(); ++i) {
    const Box2 body{parked[i].position, parked[i].heading, kCarLength / 2, kCarWidth / 2};
    EXPECT_EQ(world.map.KindAt(world.map.TileAt(parked[i].position)), map::TileKind::kStraight);
    const map::LaneProjection lane = world.graph.Nearest(parked[i].position, parked[i].heading);
    EXPECT_NEAR(map::WrapAngle(lane.lane.heading - parked[i].heading), 0.0, 1e-9);    // along its lane
    EXPECT_NEAR(lane.lateral_offset, -(kParkedLateral - map::kLaneWidth / 2), 1e-9);  // on its right
    for (const Eigen::Vector2d& corner : Corners(body)) {
      nearest_lane = std::min(nearest_lane, world.graph.Nearest(corner).distance);
    }
    for (const map::MapObject& object : world.map.objects) EXPECT_FALSE(Overlap(body, FootprintOf(object)));
    for (std::size_t j = 0; j < i; ++j) {
      EXPECT_FALSE(Overlap(body, {parked[j].position, parked[j].heading, kCarLength / 2, kCarWidth / 2}));
    }
  }
  std::cout << all << " parked cars on " << world.map.name << ", nearest lane centre to a body corner " << nearest_lane
            << " m\n";
  EXPECT_GE(nearest_lane, map::kLaneWidth / 2);  // off the road surface
}

TEST(TrafficPlanTest, MovingCarsStartSpreadAlongTheLanesOutsideJunctions) {
  const TrafficWorld probe(LoadShipped("scenes/driving/val/02_urban.map"), Config(0, 0, 0));
  const TrafficWorld world(LoadShipped("scenes/driving/val/02_urban.map"),
                           Config(probe.plan.moving_car_capacity(), 0, 0));
  const std::vector<TrafficPlan::CarStart>& starts = world.plan.car_starts();
  double closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < starts.size(); ++i) {
    EXPECT_EQ(world.plan.JunctionOf(starts[i].lane.segment), -1);
    EXPECT_GE(starts[i].cruise_speed, kMinCruiseSpeed);
    EXPECT_LE(starts[i].cruise_speed, kMaxCruiseSpeed);
    for (std::size_t j = 0; j < i; ++j) {
      if (std::abs(map::WrapAngle(starts[i].lane.heading - starts[j].lane.heading)) >= std::numbers::pi / 2) continue;
      closest = std::min(closest, (starts[i].lane.position - starts[j].lane.position).norm());
    }
  }
  std::cout << starts.size() << " start places, closest two running the same way " << closest << " m apart\n";
  EXPECT_GE(closest, kStartSpacing);
}

TEST(TrafficPlanTest, SameSeedSamePlanAnotherSeedAnother) {
  const auto plan_of = [](uint64_t seed) {
    return TrafficWorld(LoadShipped("scenes/driving/test/03_urban.map"), Config(10, 20, 10, seed));
  };
  const TrafficWorld a = plan_of(3), b = plan_of(3), c = plan_of(4);
  ASSERT_EQ(a.plan.parked_cars().size(), 20u);
  bool parked_differ = false, starts_differ = false;
  for (std::size_t i = 0; i < 20; ++i) {
    EXPECT_EQ(a.plan.parked_cars()[i].position, b.plan.parked_cars()[i].position);
    parked_differ = parked_differ || a.plan.parked_cars()[i].position != c.plan.parked_cars()[i].position;
  }
  for (std::size_t i = 0; i < 10; ++i) {
    EXPECT_EQ(a.plan.car_starts()[i].lane.position, b.plan.car_starts()[i].lane.position);
    EXPECT_EQ(a.plan.car_starts()[i].rng_seed, b.plan.car_starts()[i].rng_seed);
    EXPECT_EQ(a.plan.walker_starts()[i].path, b.plan.walker_starts()[i].path);
    starts_differ = starts_differ || a.plan.car_starts()[i].lane.position != c.plan.car_starts()[i].lane.position;
  }
  for (std::size_t j = 0; j < a.plan.junctions().size(); ++j) {
    EXPECT_EQ(a.plan.junctions()[j].phase_s, b.plan.junctions()[j].phase_s);
  }
  EXPECT_TRUE(parked_differ);
  EXPECT_TRUE(starts_differ);
}

TEST(TrafficPlanTest, WithoutLightsJunctionsStayButNothingIsHeld) {
  TrafficConfig config = Config(0, 0, 0);
  config.traffic_lights = false;
  const TrafficWorld world(GridMap(), config);
  EXPECT_TRUE(world.plan.lights().empty());
  EXPECT_EQ(world.plan.junctions().size(), 5u);
  for (const map::LaneSegment& segment : world.graph.segments()) EXPECT_EQ(world.plan.LightControlling(segment.id), -1);
  for (const TrafficPlan::WalkPath& walk : world.plan.walk_paths()) EXPECT_EQ(walk.light, -1);
}

TEST(TrafficPlanTest, AnObjectOnTheRoadIsAnObstacleAndNoCarStartsAtIt) {
  // A ring of 3 x 3 tiles with a barrier on the eastbound lane of the bottom row.
  const map::Map ring =
      map::ParseMap("sim4cv-map 1\nname ring\ntile_size 20\ngrid 3 3\n###\n#.#\n###\nend\nobject obstacle 0 -22 0\n");
  const TrafficWorld probe(ring, Config(0, 0, 0));
  const TrafficWorld world(ring, Config(probe.plan.moving_car_capacity(), 0, 0));
  ASSERT_EQ(world.plan.road_obstacles().size(), 1u);
  EXPECT_EQ(world.plan.road_obstacles()[0].position, Eigen::Vector2d(0, -22));
  for (const TrafficPlan::CarStart& start : world.plan.car_starts()) {
    EXPECT_GE((start.lane.position - Eigen::Vector2d(0, -22)).norm(), kCarLength / 2);
  }
}

// The message TrafficPlan throws for `config` on the grid map.
std::string ErrorFor(const TrafficConfig& config) {
  const map::Map map = GridMap();
  const map::RoadGraph graph(map);
  try {
    TrafficPlan plan(map, graph, config);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "no error";
}

TEST(TrafficPlanTest, AConfigThatCannotBeMetNamesTheFlagAndValue) {
  const TrafficWorld world(GridMap(), Config(0, 0, 0));
  const std::string cars = std::to_string(world.plan.moving_car_capacity());
  EXPECT_EQ(ErrorFor(Config(500, 0, 0)), "--traffic-cars 500: the map's lanes hold at most " + cars + " cars");
  EXPECT_NE(ErrorFor(Config(0, 100000, 0)).find("--traffic-parked 100000: the map's kerbs hold at most "),
            std::string::npos);
  EXPECT_NE(ErrorFor(Config(0, 0, 1000)).find("--traffic-pedestrians 1000: the map's crosswalks hold at most 64"),
            std::string::npos);
  EXPECT_NE(ErrorFor(Config(-1, 0, 0)).find("--traffic-cars -1: must be >= 0"), std::string::npos);
  EXPECT_NE(ErrorFor(Config(0, -2, 0)).find("--traffic-parked -2"), std::string::npos);
  EXPECT_NE(ErrorFor(Config(0, 0, -3)).find("--traffic-pedestrians -3"), std::string::npos);
  TrafficConfig timing = Config(0, 0, 0);
  timing.green_s = 0;
  EXPECT_EQ(ErrorFor(timing), "--traffic-green 0: must be a time > 0 s");
  timing.green_s = 8;
  timing.yellow_s = -1;
  EXPECT_EQ(ErrorFor(timing), "--traffic-yellow -1: must be a time >= 0 s");
  timing.yellow_s = 2;
  timing.all_red_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(ErrorFor(timing), "--traffic-all-red nan: must be a time >= 0 s");
}

}  // namespace
}  // namespace sim4cv::traffic
