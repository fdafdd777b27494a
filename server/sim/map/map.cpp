#include "server/sim/map/map.h"

#include <cmath>
#include <numbers>

namespace sim4cv::map {

const char* SurroundingsName(Surroundings s) { return s == Surroundings::kUrban ? "urban" : "desert"; }

std::optional<Surroundings> SurroundingsFromName(const std::string& name) {
  if (name == "desert") return Surroundings::kDesert;
  if (name == "urban") return Surroundings::kUrban;
  return std::nullopt;
}

const char* ObjectKindName(ObjectKind kind) {
  switch (kind) {
    case ObjectKind::kHouse:
      return "house";
    case ObjectKind::kTree:
      return "tree";
    case ObjectKind::kLantern:
      return "lantern";
    case ObjectKind::kPark:
      return "park";
    case ObjectKind::kObstacle:
      return "obstacle";
  }
  return "?";
}

std::optional<ObjectKind> ObjectKindFromName(const std::string& name) {
  for (ObjectKind kind : kObjectKinds) {
    if (name == ObjectKindName(kind)) return kind;
  }
  return std::nullopt;
}

const ObjectShape& ShapeOf(ObjectKind kind) {
  // base_radius: the footprint's half diagonal, except for trees, whose trunk
  // (0.3 m) plus room for roots is what must stay off the road; their crowns
  // may overhang it, which is what hides the road from a camera above.
  static const ObjectShape kHouse{5.0, 4.0, 7.0, 0.0, 6.4};
  static const ObjectShape kTree{0.3, 0.3, 9.0, 3.5, 1.0};
  static const ObjectShape kLantern{0.15, 0.15, 6.0, 0.0, 0.3};
  static const ObjectShape kPark{8.0, 8.0, 0.05, 0.0, 11.4};
  static const ObjectShape kObstacle{1.0, 0.5, 1.0, 0.0, 1.2};
  switch (kind) {
    case ObjectKind::kHouse:
      return kHouse;
    case ObjectKind::kTree:
      return kTree;
    case ObjectKind::kLantern:
      return kLantern;
    case ObjectKind::kPark:
      return kPark;
    case ObjectKind::kObstacle:
      return kObstacle;
  }
  return kHouse;
}

Eigen::Vector2d Map::TileCentre(TileCoord t) const {
  return {(t.col + 0.5 - width / 2.0) * tile_size, (height / 2.0 - t.row - 0.5) * tile_size};
}

TileCoord Map::TileAt(const Eigen::Vector2d& p) const {
  return {static_cast<int>(std::floor(p.x() / tile_size + width / 2.0)),
          static_cast<int>(std::floor(height / 2.0 - p.y() / tile_size))};
}

const Route* Map::FindRoute(const std::string& route_name) const {
  for (const Route& route : routes) {
    if (route.name == route_name) return &route;
  }
  return nullptr;
}

double TileRoadLength(TileKind kind, double tile_size) {
  switch (kind) {
    case TileKind::kEmpty:
      return 0.0;
    case TileKind::kDeadEnd:
      return tile_size / 2;
    case TileKind::kStraight:
      return tile_size;
    case TileKind::kCurve:
      return std::numbers::pi * tile_size / 4;
    case TileKind::kTJunction:
      return 1.5 * tile_size;
    case TileKind::kCrossroads:
      return 2.0 * tile_size;
  }
  return 0.0;
}

double RoadLength(const Map& map) {
  double total = 0.0;
  for (EdgeMask mask : map.road) total += TileRoadLength(KindOf(mask), map.tile_size);
  return total;
}

int CountRoadComponents(const Map& map) {
  std::vector<bool> seen(map.road.size(), false);
  std::vector<TileCoord> stack;
  int components = 0;
  for (std::size_t start = 0; start < map.road.size(); ++start) {
    if (map.road[start] == 0 || seen[start]) continue;
    ++components;
    seen[start] = true;
    stack.push_back(map.CoordOf(start));
    while (!stack.empty()) {
      const TileCoord t = stack.back();
      stack.pop_back();
      for (Edge e : kEdges) {
        const TileCoord n = Neighbour(t, e);
        if (!Has(map.ConnectionsAt(t), e) || !map.InGrid(n) || seen[map.Index(n)]) continue;
        seen[map.Index(n)] = true;
        stack.push_back(n);
      }
    }
  }
  return components;
}

}  // namespace sim4cv::map
