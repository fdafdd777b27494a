// Unit tests of the lane graph's queries (server/sim/map/road_queries.cpp)
// and of road length (map.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "server/sim/map/road_graph.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/map_test_support.h"

namespace sim4cv::map {
namespace {

using testing::ExpectNear;
using testing::ParseRows;

constexpr double kPi = std::numbers::pi;

SegmentId Through(const RoadGraph& graph, TileCoord tile, Edge entry, Edge exit) {
  const auto id = graph.Find(tile, entry, exit);
  EXPECT_TRUE(id.has_value());
  return id.value_or(0);
}

TEST(RoadQueriesTest, NearestOnAStraight) {
  const Map map = ParseRows({"###"});  // tile 1,0 on the origin; eastbound lane y = -2, westbound y = +2
  const RoadGraph graph(map);
  const LaneProjection p = graph.Nearest({3, -1});
  EXPECT_EQ(p.lane.segment, Through(graph, {1, 0}, Edge::kWest, Edge::kEast));
  EXPECT_NEAR(p.lane.s, 13, 1e-9);
  ExpectNear(p.lane.position, {3, -2});
  EXPECT_NEAR(p.lane.heading, 0, 1e-12);
  EXPECT_NEAR(p.distance, 1, 1e-9);
  EXPECT_NEAR(p.lateral_offset, 1, 1e-9);  // left of an eastbound lane is north
  EXPECT_NEAR(graph.Nearest({3, -3.5}).lateral_offset, -1.5, 1e-9);
  // A westbound car just south of the centre line belongs to the westbound lane.
  const LaneProjection west = graph.Nearest({3, -1}, kPi);
  EXPECT_EQ(west.lane.segment, Through(graph, {1, 0}, Edge::kEast, Edge::kWest));
  EXPECT_NEAR(west.lane.s, 7, 1e-9);
  EXPECT_NEAR(west.lateral_offset, 3, 1e-9);
  // An eastbound car drifted over the centre line still belongs to its own lane.
  const LaneProjection drifted = graph.Nearest({3, 1.5}, 0.3);
  EXPECT_NEAR(drifted.lane.heading, 0, 1e-12);
  EXPECT_NEAR(drifted.lateral_offset, 3.5, 1e-9);
}

TEST(RoadQueriesTest, NearestOnACurve) {
  const Map map = ParseRows({"##", "##"});  // every tile's curve is about the origin
  const RoadGraph graph(map);
  // 9 m from the origin in the north-west tile: 1 m outside the clockwise
  // (right-turning, radius 8) lane, 3 m inside the counter-clockwise one.
  const Eigen::Vector2d p = 9 * Eigen::Vector2d(-std::sqrt(0.5), std::sqrt(0.5));
  const LaneProjection nearest = graph.Nearest(p);
  const LaneSegment& segment = graph.segment(nearest.lane.segment);
  EXPECT_EQ(segment.tile, (TileCoord{0, 0}));
  EXPECT_EQ(segment.turn, Turn::kRight);
  EXPECT_NEAR(nearest.distance, 1, 1e-9);
  EXPECT_NEAR(nearest.lane.heading, kPi / 4, 1e-9);  // clockwise at 135 degrees: heading north-east
  EXPECT_NEAR(nearest.lane.s, segment.length() / 2, 1e-9);
  EXPECT_NEAR(nearest.lateral_offset, 1, 1e-9);  // outside a right turn is to the left
  const LaneProjection ccw = graph.Nearest(p, -3 * kPi / 4);
  EXPECT_EQ(graph.segment(ccw.lane.segment).turn, Turn::kLeft);
  EXPECT_NEAR(ccw.lateral_offset, 3, 1e-9);  // inside a left turn is to the left
}

TEST(RoadQueriesTest, PointsAheadAreEvenlySpacedAcrossTiles) {
  const Map map = ParseRows({"#######"});
  const RoadGraph graph(map);
  const LanePoint start = graph.At(Through(graph, {1, 0}, Edge::kWest, Edge::kEast), 15);  // x = -35
  const std::vector<LanePoint> ahead = graph.PointsAhead(start, 2, 4);
  ASSERT_EQ(ahead.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    ExpectNear(ahead[i].position, {-35 + 2.0 * (i + 1), -2});
    EXPECT_NEAR(ahead[i].heading, 0, 1e-12);
  }
  EXPECT_EQ(graph.segment(ahead[3].segment).tile, (TileCoord{2, 0}));
  EXPECT_NEAR(ahead[3].s, 3, 1e-9);
}

TEST(RoadQueriesTest, PointsAheadFollowTheArcsOfARing) {
  const Map map = ParseRows({"##", "##"});  // the clockwise lane is one circle of radius 8
  const RoadGraph graph(map);
  const double step = 0.5;
  const std::vector<LanePoint> ahead =
      graph.PointsAhead(graph.At(Through(graph, {0, 0}, Edge::kSouth, Edge::kEast), 0), step, 300);
  const double chord = 2 * 8 * std::sin(step / 16);
  Eigen::Vector2d previous(-8, 0);
  for (const LanePoint& p : ahead) {
    EXPECT_NEAR(p.position.norm(), 8, 1e-9);
    EXPECT_NEAR((p.position - previous).norm(), chord, 1e-9);
    previous = p.position;
  }
}

// A crossroads with a dead end on each arm; start 1 m before leaving the
// west arm towards it.
class JunctionTest : public ::testing::Test {
 protected:
  const Map map_ = ParseRows({".#.", "###", ".#."});
  const RoadGraph graph_{map_};
  const SegmentId west_arm_ = Through(graph_, {0, 1}, Edge::kEast, Edge::kEast);
  const LanePoint start_ = graph_.At(west_arm_, graph_.segment(west_arm_).length() - 1);

  // The turn taken on each pass through the crossroads.
  std::vector<Turn> CrossroadsTurns(const std::vector<LanePoint>& points) const {
    std::vector<Turn> turns;
    SegmentId previous = -1;
    for (const LanePoint& p : points) {
      const LaneSegment& s = graph_.segment(p.segment);
      if (s.tile == TileCoord{1, 1} && p.segment != previous) turns.push_back(s.turn);
      previous = p.segment;
    }
    return turns;
  }
};

TEST_F(JunctionTest, TurnSequenceChoosesAtEachJunction) {
  const std::vector<Turn> left_then_right = {Turn::kLeft, Turn::kRight};
  const std::vector<LanePoint> points = graph_.PointsAhead(start_, 2, 35, left_then_right);
  // Left into the north arm, round its dead end, then right: back west.
  EXPECT_EQ(CrossroadsTurns(points), left_then_right);
  EXPECT_EQ(graph_.segment(points[1].segment).tile, (TileCoord{1, 1}));
  EXPECT_EQ(graph_.segment(points[15].segment).tile, (TileCoord{1, 0}));
  EXPECT_EQ(graph_.segment(points.back().segment).tile, (TileCoord{0, 1}));
  // No turns given: straight on.
  EXPECT_EQ(CrossroadsTurns(graph_.PointsAhead(start_, 2, 10)), std::vector<Turn>{Turn::kStraight});
}

TEST_F(JunctionTest, CallbackSeesTheOptionsInTurnOrder) {
  int calls = 0;
  const JunctionChooser choose = [&](const LaneSegment& current, std::span<const SegmentId> options) {
    ++calls;
    EXPECT_EQ(current.id, west_arm_);
    EXPECT_EQ(options.size(), 3u);
    for (std::size_t i = 0; i < options.size(); ++i) EXPECT_EQ(graph_.segment(options[i]).turn, static_cast<Turn>(i));
    return std::size_t{1};  // right
  };
  const std::vector<LanePoint> points = graph_.PointsAhead(start_, 2, 5, choose);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(graph_.segment(points[0].segment).turn, Turn::kRight);
  const JunctionChooser bad = [](const LaneSegment&, std::span<const SegmentId>) { return std::size_t{3}; };
  EXPECT_THROW(graph_.PointsAhead(start_, 2, 5, bad), std::invalid_argument);
  EXPECT_THROW(graph_.PointsAhead(start_, 0, 5), std::invalid_argument);
}

TEST(RoadQueriesTest, NearestOnARouteStaysOnItsLanesAndItsPointsAheadTurnWithIt) {
  // From the west, left at the crossroads (tile 2,1 on the origin) into the north arm.
  const Map map = ParseRows({"..#..", "#####", "..#.."}, 20, "route left open\ntiles 0,1 1,1 2,1 2,0\n");
  const RoadGraph graph(map);
  const std::vector<SegmentId> route = graph.RouteSegments(map.routes[0]);
  ASSERT_EQ(route.size(), 2u);
  const SegmentId left_turn = Through(graph, {2, 1}, Edge::kWest, Edge::kNorth);
  EXPECT_EQ(route[1], left_turn);
  // Straight on past the crossroads, on the eastbound lane of the east arm:
  // 0 m from some lane, but 20.31 m from the route's (the left turn's arc,
  // radius 12 m about the crossroads' north-west corner (-10, 10)).
  EXPECT_NEAR(graph.Nearest({20, -2}).distance, 0, 1e-9);
  const LaneProjection missed = graph.NearestOnRoute({20, -2}, route);
  EXPECT_EQ(missed.lane.segment, left_turn);
  EXPECT_NEAR(missed.distance, std::hypot(30.0, 12.0) - 12, 1e-9);
  // The points ahead follow the route's turn; plain ones go straight on.
  const LanePoint before = graph.At(route[0], graph.segment(route[0]).length() - 1);
  EXPECT_EQ(graph.PointsAlongRoute(before, 2, 3, route).back().segment, left_turn);
  EXPECT_EQ(graph.segment(graph.PointsAhead(before, 2, 3).back().segment).turn, Turn::kStraight);
  EXPECT_THROW(graph.NearestOnRoute({0, 0}, {}), std::invalid_argument);
}

TEST(RoadQueriesTest, MissingTurnFallsBackToStraightThenRight) {
  const Map map = ParseRows({"###", ".#."});  // a T: from the stem only right and left
  const RoadGraph graph(map);
  const SegmentId stem = Through(graph, {1, 1}, Edge::kNorth, Edge::kNorth);
  const auto& options = graph.segment(stem).successors;
  ASSERT_EQ(options.size(), 2u);
  EXPECT_EQ(graph.segment(options[graph.ChooseTurn(options, Turn::kStraight)]).turn, Turn::kRight);
  EXPECT_EQ(graph.segment(options[graph.ChooseTurn(options, Turn::kLeft)]).turn, Turn::kLeft);
  // Westbound along the top: straight on or left into the stem.
  const auto& along = graph.segment(Through(graph, {2, 0}, Edge::kWest, Edge::kWest)).successors;
  const SegmentId west = Through(graph, {1, 0}, Edge::kEast, Edge::kWest);
  EXPECT_EQ(along[graph.ChooseTurn(along, Turn::kRight)], west);
  EXPECT_EQ(along[graph.ChooseTurn(along, Turn::kLeft)], Through(graph, {1, 0}, Edge::kEast, Edge::kSouth));
}

TEST(RoadQueriesTest, ClosedRoutesSampleTheirLane) {
  const std::string ccw = "route ccw closed\ntiles 0,0 0,1 1,1 1,0\n";
  const std::string cw = "route cw closed\ntiles 0,0 1,0 1,1 0,1\n";
  const Map map = ParseRows({"##", "##"}, 20, ccw + cw);
  const RoadGraph graph(map);
  // Counter-clockwise, right-hand traffic keeps to the outside: radius 12.
  const SampledPath outer = graph.SampleRoute(*map.FindRoute("ccw"), 1.0);
  EXPECT_TRUE(outer.closed);
  EXPECT_NEAR(outer.length, 24 * kPi, 1e-9);
  ASSERT_EQ(outer.points.size(), 4u * 19u);  // each quarter (18.85 m) in 19 equal parts
  for (std::size_t i = 0; i < outer.points.size(); ++i) {
    EXPECT_NEAR(outer.points[i].norm(), 12, 1e-9);
    const Eigen::Vector2d tangent(std::cos(outer.heading[i]), std::sin(outer.heading[i]));
    EXPECT_NEAR(tangent.dot(outer.points[i]), 0, 1e-9);
    EXPECT_GT(outer.points[i].x() * tangent.y() - outer.points[i].y() * tangent.x(), 0);  // counter-clockwise
    EXPECT_NEAR(outer.arc_length[i], i * 6 * kPi / 19, 1e-9);
  }
  const SampledPath inner = graph.SampleRoute(*map.FindRoute("cw"), 1.0);
  EXPECT_NEAR(inner.length, 16 * kPi, 1e-9);
  EXPECT_NEAR(inner.points[7].norm(), 8, 1e-9);
  EXPECT_EQ(graph.RouteSegments(*map.FindRoute("cw")).size(), 4u);
}

TEST(RoadQueriesTest, OpenRoutesRunFromLeavingTheFirstTileToEnteringTheLast) {
  const Map map = ParseRows({"#####"}, 20, "route east open\ntiles 0,0 1,0 2,0 3,0 4,0\n");
  const RoadGraph graph(map);
  const SampledPath path = graph.SampleRoute(map.routes[0], 1.0);
  EXPECT_FALSE(path.closed);
  EXPECT_NEAR(path.length, 60, 1e-9);
  ASSERT_EQ(path.points.size(), 61u);
  ExpectNear(path.points.front(), {-30, -2});
  ExpectNear(path.points.back(), {30, -2});
  EXPECT_NEAR(path.arc_length.back(), 60, 1e-9);
  const Route broken{"broken", false, {{0, 0}, {2, 0}, {3, 0}}};
  EXPECT_THROW(graph.RouteSegments(broken), std::invalid_argument);
}

TEST(RoadLengthTest, SumsTheCentreLineOfEveryTile) {
  EXPECT_NEAR(TileRoadLength(TileKind::kStraight, 20), 20, 1e-12);
  EXPECT_NEAR(TileRoadLength(TileKind::kCurve, 20), 5 * kPi, 1e-12);
  EXPECT_NEAR(TileRoadLength(TileKind::kTJunction, 20), 30, 1e-12);
  EXPECT_NEAR(TileRoadLength(TileKind::kCrossroads, 20), 40, 1e-12);
  EXPECT_NEAR(TileRoadLength(TileKind::kDeadEnd, 20), 10, 1e-12);
  EXPECT_NEAR(TileRoadLength(TileKind::kEmpty, 20), 0, 1e-12);
  // A crossroads, a straight, a curve and four dead ends.
  EXPECT_NEAR(RoadLength(ParseRows({".#.#", "####", ".#.."})), 40 + 20 + 5 * kPi + 4 * 10, 1e-9);
}

}  // namespace
}  // namespace sim4cv::map
