// The tile grid's vocabulary: edges, connection masks, tile coordinates and
// the kind of road a tile holds. Header-only: every part of the map module
// uses it and none of it needs a .cpp.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace sim4cv::map {

// The four sides of a tile. Row 0 is the grid's north edge, so going north
// decreases the row; world x is east and world y is north.
enum class Edge : uint8_t { kNorth = 0, kEast = 1, kSouth = 2, kWest = 3 };
inline constexpr std::array<Edge, 4> kEdges = {Edge::kNorth, Edge::kEast, Edge::kSouth, Edge::kWest};

// Which sides of a tile its road leaves through: bit (1 << edge), so
// N = 1, E = 2, S = 4, W = 8 (the hex digit of an explicit tile code).
using EdgeMask = uint8_t;

constexpr EdgeMask Bit(Edge e) { return static_cast<EdgeMask>(1u << static_cast<unsigned>(e)); }
constexpr bool Has(EdgeMask mask, Edge e) { return (mask & Bit(e)) != 0; }
constexpr Edge Opposite(Edge e) { return static_cast<Edge>((static_cast<unsigned>(e) + 2) % 4); }

// Unit vector pointing out of a tile through edge `e`, in world axes.
inline Eigen::Vector2d Outward(Edge e) {
  switch (e) {
    case Edge::kNorth:
      return {0, 1};
    case Edge::kEast:
      return {1, 0};
    case Edge::kSouth:
      return {0, -1};
    case Edge::kWest:
      return {-1, 0};
  }
  return {0, 0};
}

struct TileCoord {
  int col = 0;  // 0 = west edge of the grid
  int row = 0;  // 0 = north edge of the grid
  friend bool operator==(const TileCoord&, const TileCoord&) = default;
};

// The tile across edge `e` (it may lie outside the grid).
constexpr TileCoord Neighbour(TileCoord t, Edge e) {
  switch (e) {
    case Edge::kNorth:
      return {t.col, t.row - 1};
    case Edge::kEast:
      return {t.col + 1, t.row};
    case Edge::kSouth:
      return {t.col, t.row + 1};
    case Edge::kWest:
      return {t.col - 1, t.row};
  }
  return t;
}

// The edge of `from` that `to` lies across, if they are 4-neighbours.
constexpr bool EdgeTowards(TileCoord from, TileCoord to, Edge* edge) {
  for (Edge e : kEdges) {
    if (Neighbour(from, e) == to) {
      *edge = e;
      return true;
    }
  }
  return false;
}

// What a road tile is, from how many sides it connects and which.
enum class TileKind : uint8_t { kEmpty, kDeadEnd, kStraight, kCurve, kTJunction, kCrossroads };

constexpr int CountEdges(EdgeMask mask) {
  return ((mask >> 0) & 1) + ((mask >> 1) & 1) + ((mask >> 2) & 1) + ((mask >> 3) & 1);
}

constexpr TileKind KindOf(EdgeMask mask) {
  switch (CountEdges(mask)) {
    case 0:
      return TileKind::kEmpty;
    case 1:
      return TileKind::kDeadEnd;
    case 2:
      return (mask == 0b0101 || mask == 0b1010) ? TileKind::kStraight : TileKind::kCurve;
    case 3:
      return TileKind::kTJunction;
    default:
      return TileKind::kCrossroads;
  }
}

// Whether a lane enters a tile with connections `mask` through `entry` and
// leaves through `exit`: both must be connected, and only a dead end turns
// back the way it came.
constexpr bool CanPass(EdgeMask mask, Edge entry, Edge exit) {
  return Has(mask, entry) && Has(mask, exit) && (entry != exit || CountEdges(mask) == 1);
}

constexpr const char* KindName(TileKind kind) {
  switch (kind) {
    case TileKind::kEmpty:
      return "empty";
    case TileKind::kDeadEnd:
      return "dead end";
    case TileKind::kStraight:
      return "straight";
    case TileKind::kCurve:
      return "curve";
    case TileKind::kTJunction:
      return "T-junction";
    case TileKind::kCrossroads:
      return "crossroads";
  }
  return "?";
}

}  // namespace sim4cv::map
