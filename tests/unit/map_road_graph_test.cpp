// Unit tests of the lane graph's geometry (server/sim/map/road_graph.cpp, lane_curve.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "server/sim/map/generator.h"
#include "server/sim/map/road_graph.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/map_test_support.h"

namespace sim4cv::map {
namespace {

using testing::ExpectNear;
using testing::ParseRows;

constexpr double kPi = std::numbers::pi;

const LaneSegment& SegmentThrough(const RoadGraph& graph, TileCoord tile, Edge entry, Edge exit) {
  const auto id = graph.Find(tile, entry, exit);
  EXPECT_TRUE(id.has_value()) << "no segment " << tile.col << "," << tile.row;
  return graph.segment(id.value_or(0));
}

TEST(LaneCurveTest, ArcPointsAndProjection) {
  // A left quarter circle of radius 10 about the origin, from (10, 0) heading north.
  LaneCurve curve({10, 0}, kPi / 2);
  curve.Arc(10, kPi / 2).Straight(5);
  EXPECT_NEAR(curve.length(), 5 * kPi + 5, 1e-12);
  ExpectNear(curve.PointAt(5 * kPi / 2), {10 * std::cos(kPi / 4), 10 * std::sin(kPi / 4)});
  ExpectNear(curve.PointAt(curve.length()), {-5, 10});
  EXPECT_NEAR(curve.HeadingAt(curve.length()), kPi, 1e-12);
  EXPECT_NEAR(curve.CurvatureAt(1), 0.1, 1e-12);
  const LaneCurve::Nearest inside = curve.Project({2, 2});
  EXPECT_NEAR(inside.s, 5 * kPi / 2, 1e-9);
  EXPECT_NEAR(inside.distance, 10 - std::sqrt(8.0), 1e-9);
  EXPECT_NEAR(curve.Project({12, -3}).s, 0.0, 1e-12);  // before the start
  EXPECT_NEAR(curve.Project({-9, 11}).s, curve.length(), 1e-12);
  EXPECT_NEAR(WrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(WrapAngle(-kPi), kPi, 1e-12);
}

TEST(RoadGraphTest, TurnsFromEdges) {
  EXPECT_EQ(TurnOf(Edge::kSouth, Edge::kNorth), Turn::kStraight);
  EXPECT_EQ(TurnOf(Edge::kSouth, Edge::kEast), Turn::kRight);  // heading north, then east
  EXPECT_EQ(TurnOf(Edge::kSouth, Edge::kWest), Turn::kLeft);
  EXPECT_EQ(TurnOf(Edge::kEast, Edge::kEast), Turn::kUTurn);
  EXPECT_EQ(TurnOf(Edge::kWest, Edge::kNorth), Turn::kLeft);  // heading east, then north
}

int SegmentsIn(const RoadGraph& graph, TileCoord tile) {
  int n = 0;
  for (const LaneSegment& s : graph.segments()) n += s.tile == tile;
  return n;
}

TEST(RoadGraphTest, SegmentsPerTileKind) {
  const RoadGraph graph(ParseRows({".#.#", "####", ".#.."}));
  EXPECT_EQ(SegmentsIn(graph, {1, 1}), 12);  // crossroads: 4 ways in, 3 ways on from each
  EXPECT_EQ(SegmentsIn(graph, {3, 1}), 2);   // curve
  EXPECT_EQ(SegmentsIn(graph, {2, 1}), 2);   // straight
  EXPECT_EQ(SegmentsIn(graph, {1, 0}), 1);   // dead end: the U-turn
  const RoadGraph t_graph(ParseRows({"###", ".#."}));
  EXPECT_EQ(SegmentsIn(t_graph, {1, 0}), 6);  // T-junction: 3 ways in, 2 ways on
  EXPECT_TRUE(t_graph.Find({1, 0}, Edge::kWest, Edge::kEast).has_value());
  EXPECT_FALSE(t_graph.Find({1, 0}, Edge::kWest, Edge::kNorth).has_value());
  EXPECT_FALSE(t_graph.Find({5, 0}, Edge::kWest, Edge::kEast).has_value());
}

TEST(RoadGraphTest, StraightLanesAreTwoMetresEitherSideOfTheCentreLine) {
  const Map map = ParseRows({"###"});  // tile 1,0 is centred on the origin, road along y = 0
  const RoadGraph graph(map);
  const LaneSegment& east = SegmentThrough(graph, {1, 0}, Edge::kWest, Edge::kEast);
  const LaneSegment& west = SegmentThrough(graph, {1, 0}, Edge::kEast, Edge::kWest);
  EXPECT_NEAR(east.length(), 20, 1e-12);
  for (double s = 0; s <= 20; s += 2.5) {
    ExpectNear(east.curve.PointAt(s), {-10 + s, -2});  // right-hand traffic: eastbound on the south side
    ExpectNear(west.curve.PointAt(s), {10 - s, 2});
    EXPECT_NEAR(east.curve.HeadingAt(s), 0, 1e-12);
    EXPECT_NEAR(west.curve.HeadingAt(s), kPi, 1e-12);
  }
}

TEST(RoadGraphTest, CurveLanesAreArcsAboutTheTileCorner) {
  for (double tile_size : {12.0, 20.0, 50.0}) {
    const Map map = ParseRows({"##", "##"}, tile_size);
    const RoadGraph graph(map);
    // Tile 0,0 joins east and south; its corner between them is the origin.
    const LaneSegment& right = SegmentThrough(graph, {0, 0}, Edge::kSouth, Edge::kEast);
    const LaneSegment& left = SegmentThrough(graph, {0, 0}, Edge::kEast, Edge::kSouth);
    EXPECT_EQ(right.turn, Turn::kRight);
    EXPECT_EQ(left.turn, Turn::kLeft);
    const double half = tile_size / 2;
    EXPECT_NEAR(right.length(), (half - 2) * kPi / 2, 1e-9);
    EXPECT_NEAR(left.length(), (half + 2) * kPi / 2, 1e-9);
    for (double f = 0; f <= 1.0; f += 0.125) {
      EXPECT_NEAR(right.curve.PointAt(f * right.length()).norm(), half - 2, 1e-9);
      EXPECT_NEAR(left.curve.PointAt(f * left.length()).norm(), half + 2, 1e-9);
    }
    EXPECT_NEAR(right.curve.CurvatureAt(1), -1 / (half - 2), 1e-12);
    EXPECT_NEAR(left.curve.CurvatureAt(1), 1 / (half + 2), 1e-12);
    ExpectNear(right.curve.PointAt(0), {-(half - 2), 0});
  }
}

TEST(RoadGraphTest, DeadEndTurnsAroundTheTileCentre) {
  const Map map = ParseRows({"##"});
  const RoadGraph graph(map);
  const LaneSegment& u_turn = SegmentThrough(graph, {1, 0}, Edge::kWest, Edge::kWest);
  EXPECT_EQ(u_turn.turn, Turn::kUTurn);
  EXPECT_NEAR(u_turn.length(), 20 + 2 * kPi, 1e-9);
  ExpectNear(u_turn.curve.PointAt(0), {0, -2});
  ExpectNear(u_turn.curve.PointAt(10 + kPi), {12, 0});  // half way round: the far end of the tile's turn
  ExpectNear(u_turn.curve.PointAt(u_turn.length()), {0, 2});
  EXPECT_NEAR(u_turn.curve.HeadingAt(u_turn.length()), kPi, 1e-12);
}

// Consecutive segments meet within 1 mm and with the same heading, and the
// links are consistent both ways.
void ExpectContinuous(const RoadGraph& graph) {
  for (const LaneSegment& segment : graph.segments()) {
    ASSERT_FALSE(segment.successors.empty()) << "segment " << segment.id;
    const Eigen::Vector2d end = segment.curve.PointAt(segment.length());
    const double end_heading = segment.curve.HeadingAt(segment.length());
    for (SegmentId id : segment.successors) {
      const LaneSegment& next = graph.segment(id);
      EXPECT_EQ(next.entry, Opposite(segment.exit));
      EXPECT_LT((next.curve.PointAt(0) - end).norm(), 1e-3) << segment.id << " -> " << id;
      EXPECT_NEAR(WrapAngle(next.curve.HeadingAt(0) - end_heading), 0, 1e-9) << segment.id << " -> " << id;
      EXPECT_NE(std::find(next.predecessors.begin(), next.predecessors.end(), segment.id), next.predecessors.end());
    }
    for (std::size_t i = 1; i < segment.successors.size(); ++i) {
      EXPECT_LT(graph.segment(segment.successors[i - 1]).turn, graph.segment(segment.successors[i]).turn);
    }
    const auto& pieces = segment.curve.pieces();
    for (std::size_t i = 1; i < pieces.size(); ++i) {
      EXPECT_LT((pieces[i - 1].PointAt(pieces[i - 1].length) - pieces[i].start).norm(), 1e-9);
    }
  }
}

TEST(RoadGraphTest, LanesAreContinuousOnHandMadeMaps) {
  ExpectContinuous(RoadGraph(ParseRows({".#.#.", "#####", ".#.#.", "##.##"}, 14)));
  ExpectContinuous(RoadGraph(ParseRows({"##", "##"}, 50)));
}

TEST(RoadGraphTest, LanesAreContinuousOnGeneratedMaps) {
  for (uint64_t seed = 1; seed <= 5; ++seed) ExpectContinuous(RoadGraph(GenerateRoads(seed, 9, 8, 20)));
}

TEST(RoadGraphTest, RejectsAMalformedMap) {
  Map map = ParseRows({"##"});
  map.road.pop_back();
  EXPECT_THROW(RoadGraph{map}, std::invalid_argument);
  map = ParseRows({"##"});
  map.tile_size = 8;
  EXPECT_THROW(RoadGraph{map}, std::invalid_argument);
}

}  // namespace
}  // namespace sim4cv::map
