// The lanes of a map as a directed graph of lane segments (docs/maps.md,
// "Road graph"). Every road has two lanes of kLaneWidth, right-hand traffic.
// A segment is one way through one tile: in through one side, out through
// another; its centre line is exact (lines and arcs, see lane_curve.h).
// Built once from an immutable Map and immutable itself.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "server/sim/map/lane_curve.h"
#include "server/sim/map/map.h"

namespace sim4cv::map {

using SegmentId = int32_t;  // index into RoadGraph::segments()

// How a segment leaves its tile relative to how it came in. The order is
// the order of a segment's successors and of ties in Nearest.
enum class Turn : uint8_t { kStraight, kRight, kLeft, kUTurn };
const char* TurnName(Turn turn);
Turn TurnOf(Edge entry, Edge exit);

struct LaneSegment {
  SegmentId id = -1;
  TileCoord tile;
  Edge entry = Edge::kNorth;  // the tile side it comes in through
  Edge exit = Edge::kNorth;   // and leaves through
  Turn turn = Turn::kStraight;
  // Straight: one line of tile_size. Turn: a quarter arc about the tile
  // corner between entry and exit, radius tile_size/2 - 2 m (right) or
  // + 2 m (left). U-turn (dead ends only): tile_size/2 in, a half circle of
  // radius 2 m about the tile centre, tile_size/2 out.
  LaneCurve curve;
  std::vector<SegmentId> successors;    // the next tile's segments entering where this one leaves
  std::vector<SegmentId> predecessors;  // the segments that lead into this one
  double length() const { return curve.length(); }
};

struct LanePoint {
  SegmentId segment = -1;
  double s = 0.0;  // arc length along the segment, metres
  Eigen::Vector2d position{0, 0};
  double heading = 0.0;  // direction of travel, radians in (-pi, pi], counter-clockwise from east
};

struct LaneProjection {
  LanePoint lane;         // the nearest point of a lane centre line
  double distance = 0.0;  // from the query point to it
  // Of the query point from the lane centre, across the direction of travel:
  // positive to the left, negative to the right (the car frame's y axis).
  double lateral_offset = 0.0;
};

// Picks the branch at a junction: returns an index into `options`, the
// successors of `current` (in Turn order). Called only when there are two or more.
using JunctionChooser = std::function<std::size_t(const LaneSegment& current, std::span<const SegmentId> options)>;

// A route's lane centre sampled as a polyline.
struct SampledPath {
  std::vector<Eigen::Vector2d> points;
  std::vector<double> arc_length;  // exact arc length along the lanes at each point, from points[0]
  std::vector<double> heading;     // direction of travel at each point, radians
  double length = 0.0;  // of the whole path; closed: including the stretch from the last point back to the first
  bool closed = false;  // closed: the first point is not repeated at the end (as a closed Polyline wants)
};

class RoadGraph {
 public:
  explicit RoadGraph(const Map& map);

  const std::vector<LaneSegment>& segments() const { return segments_; }
  const LaneSegment& segment(SegmentId id) const;
  // The segment through `tile` from `entry` to `exit`, if the road has one.
  std::optional<SegmentId> Find(TileCoord tile, Edge entry, Edge exit) const;
  // The lane point at arc length `s` (clamped to the segment).
  LanePoint At(SegmentId id, double s) const;

  // The nearest point of any lane centre to `p`. With `heading` (radians),
  // only lanes running within 90 degrees of it count (so a car in its own
  // lane is not matched to the oncoming one), unless none does. Ties go to
  // the lower segment id, i.e. straight on before turning.
  LaneProjection Nearest(const Eigen::Vector2d& p, std::optional<double> heading = std::nullopt) const;

  // The nearest point of the lanes `route` drives (RouteSegments' ids): a
  // car that missed the route's turn is measured to the route's lane, not
  // to the lane it took, and one turning through a junction to the turn's
  // arc, never to a crossing lane. Ties go to the earlier segment of the route.
  LaneProjection NearestOnRoute(const Eigen::Vector2d& p, std::span<const SegmentId> route) const;
  // `count` points every `step` metres ahead of `from`, turning where `route`
  // (RouteSegments' ids) turns; past an open route's end, or from a segment
  // not on it, straight on where possible (as PointsAhead).
  std::vector<LanePoint> PointsAlongRoute(const LanePoint& from, double step, int count,
                                          std::span<const SegmentId> route) const;

  // The lane point `distance` >= 0 metres further along the lanes.
  LanePoint Advance(const LanePoint& from, double distance, const JunctionChooser& choose) const;
  // `count` points at step, 2*step, ... count*step metres ahead of `from`
  // (the driving case study: step 2, count 4).
  std::vector<LanePoint> PointsAhead(const LanePoint& from, double step, int count,
                                     const JunctionChooser& choose) const;
  // The same, taking turns[0], turns[1], ... at successive junctions; where
  // a wished turn is missing, or the list has run out, see ChooseTurn.
  std::vector<LanePoint> PointsAhead(const LanePoint& from, double step, int count,
                                     std::span<const Turn> turns = {}) const;
  // Index into `options` of `wanted`, else of the first present of
  // straight, right, left, U-turn.
  std::size_t ChooseTurn(std::span<const SegmentId> options, Turn wanted) const;

  // The segments a route drives, in order. Closed: one per tile. Open: from
  // where it leaves its first tile to where it enters its last, so the first
  // and last tiles only set the direction. Throws std::invalid_argument if
  // the road cannot drive it.
  std::vector<SegmentId> RouteSegments(const Route& route) const;
  // The route's lane centre, sampled at most `spacing` metres apart (each
  // segment is cut into equal parts, so segment starts are always samples).
  SampledPath SampleRoute(const Route& route, double spacing) const;

  double tile_size() const { return tile_size_; }

 private:
  void AddTileSegments(const Map& map, TileCoord tile);
  void Link(const Map& map);

  double tile_size_ = 0.0;
  int width_ = 0, height_ = 0;
  std::vector<LaneSegment> segments_;
  // Per tile, indexed by entry * 4 + exit: the segment, or -1.
  std::vector<std::array<SegmentId, 16>> by_tile_;
};

}  // namespace sim4cv::map
