// Building the lane graph: segment geometry per tile, then the links.
#include "server/sim/map/road_graph.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "server/common/check.h"

namespace sim4cv::map {
namespace {

constexpr double kHalfPi = std::numbers::pi / 2;

// To the right of direction d, seen from above.
Eigen::Vector2d Right(const Eigen::Vector2d& d) { return {d.y(), -d.x()}; }

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

constexpr std::size_t Slot(Edge entry, Edge exit) {
  return static_cast<std::size_t>(entry) * 4 + static_cast<std::size_t>(exit);
}

}  // namespace

const char* TurnName(Turn turn) {
  switch (turn) {
    case Turn::kStraight:
      return "straight";
    case Turn::kRight:
      return "right";
    case Turn::kLeft:
      return "left";
    case Turn::kUTurn:
      return "u-turn";
  }
  return "?";
}

Turn TurnOf(Edge entry, Edge exit) {
  if (entry == exit) return Turn::kUTurn;
  if (exit == Opposite(entry)) return Turn::kStraight;
  // Travelling in = -Outward(entry), out = Outward(exit).
  return Cross(-Outward(entry), Outward(exit)) > 0 ? Turn::kLeft : Turn::kRight;
}

RoadGraph::RoadGraph(const Map& map) : tile_size_(map.tile_size), width_(map.width), height_(map.height) {
  SIM4CV_THROW_UNLESS(map.tile_size >= kMinTileSize, "tile size " << map.tile_size << " m is below " << kMinTileSize);
  SIM4CV_THROW_UNLESS(map.road.size() == static_cast<std::size_t>(map.width) * map.height,
                      "map '" << map.name << "' has " << map.road.size() << " tiles for a " << map.width << "x"
                              << map.height << " grid");
  std::array<SegmentId, 16> none;
  none.fill(-1);
  by_tile_.assign(map.road.size(), none);
  for (std::size_t i = 0; i < map.road.size(); ++i) AddTileSegments(map, map.CoordOf(i));
  Link(map);
}

void RoadGraph::AddTileSegments(const Map& map, TileCoord tile) {
  const EdgeMask mask = map.ConnectionsAt(tile);
  const Eigen::Vector2d centre = map.TileCentre(tile);
  const double half = tile_size_ / 2;
  const double half_lane = kLaneWidth / 2;
  for (Edge entry : kEdges) {
    // Exits in Turn order, so ids (and ties in Nearest) favour straight on.
    std::vector<std::pair<Turn, Edge>> exits;
    for (Edge exit : kEdges) {
      if (CanPass(mask, entry, exit)) exits.emplace_back(TurnOf(entry, exit), exit);
    }
    std::sort(exits.begin(), exits.end());
    for (const auto& [turn, exit] : exits) {
      // The right lane crosses the entry side half a lane to the right of
      // the road's centre line (right-hand traffic).
      const Eigen::Vector2d in = -Outward(entry);
      LaneCurve curve(centre - in * half + Right(in) * half_lane, std::atan2(in.y(), in.x()));
      switch (turn) {
        case Turn::kStraight:
          curve.Straight(tile_size_);
          break;
        case Turn::kRight:
          curve.Arc(half - half_lane, -kHalfPi);
          break;
        case Turn::kLeft:
          curve.Arc(half + half_lane, kHalfPi);
          break;
        case Turn::kUTurn:
          curve.Straight(half).Arc(half_lane, std::numbers::pi).Straight(half);
          break;
      }
      LaneSegment segment;
      segment.id = static_cast<SegmentId>(segments_.size());
      segment.tile = tile;
      segment.entry = entry;
      segment.exit = exit;
      segment.turn = turn;
      segment.curve = std::move(curve);
      by_tile_[map.Index(tile)][Slot(entry, exit)] = segment.id;
      segments_.push_back(std::move(segment));
    }
  }
}

void RoadGraph::Link(const Map& map) {
  for (LaneSegment& segment : segments_) {
    const TileCoord next = Neighbour(segment.tile, segment.exit);
    // Connections are symmetric (the parser checks), so the next tile is road.
    SIM4CV_DEMAND(map.ConnectionsAt(next) != 0);
    for (SegmentId candidate : by_tile_[map.Index(next)]) {
      if (candidate >= 0 && segments_[candidate].entry == Opposite(segment.exit)) {
        segment.successors.push_back(candidate);
      }
    }
    // by_tile_ is ordered by exit edge; successors go in Turn order.
    std::sort(segment.successors.begin(), segment.successors.end());
    for (SegmentId successor : segment.successors) segments_[successor].predecessors.push_back(segment.id);
  }
}

const LaneSegment& RoadGraph::segment(SegmentId id) const {
  SIM4CV_THROW_UNLESS(id >= 0 && static_cast<std::size_t>(id) < segments_.size(), "no lane segment " << id);
  return segments_[id];
}

std::optional<SegmentId> RoadGraph::Find(TileCoord tile, Edge entry, Edge exit) const {
  if (tile.col < 0 || tile.row < 0 || tile.col >= width_ || tile.row >= height_) return std::nullopt;
  const SegmentId id = by_tile_[static_cast<std::size_t>(tile.row) * width_ + tile.col][Slot(entry, exit)];
  if (id < 0) return std::nullopt;
  return id;
}

LanePoint RoadGraph::At(SegmentId id, double s) const {
  const LaneCurve& curve = segment(id).curve;
  s = std::clamp(s, 0.0, curve.length());
  return {id, s, curve.PointAt(s), curve.HeadingAt(s)};
}

}  // namespace sim4cv::map
