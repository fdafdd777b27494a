// A world map (docs/maps.md): the road grid, the dressing objects and the
// named routes. Immutable once loaded, like Scene; whatever a simulation step
// changes lives elsewhere (State). The lane geometry built from it is in
// road_graph.h.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "server/sim/map/grid.h"

namespace sim4cv::map {

// Every road has two lanes of this width, right-hand traffic.
inline constexpr double kLaneWidth = 4.0;
// Below this the right-turn lane radius (tile_size / 2 - 2 m) would be
// tighter than the car can steer (wheelbase 2.7 m, 35 degrees: 3.9 m).
inline constexpr double kMinTileSize = 12.0;

enum class Surroundings : uint8_t { kDesert, kUrban };
enum class ObjectKind : uint8_t { kHouse, kTree, kLantern, kPark, kObstacle };
inline constexpr ObjectKind kObjectKinds[] = {ObjectKind::kHouse, ObjectKind::kTree, ObjectKind::kLantern,
                                              ObjectKind::kPark, ObjectKind::kObstacle};

const char* SurroundingsName(Surroundings s);
std::optional<Surroundings> SurroundingsFromName(const std::string& name);
const char* ObjectKindName(ObjectKind kind);
std::optional<ObjectKind> ObjectKindFromName(const std::string& name);

// The size every object of a kind has (the map only places and turns them),
// so that renderers, physics and the generator agree.
struct ObjectShape {
  double half_x = 0, half_y = 0;  // footprint half extents along the object's own axes, m
  double height = 0;              // m
  double crown_radius = 0;        // trees only: the foliage's radius (it may overhang a road), m
  double base_radius = 0;         // what must stay off the road and clear of other objects, m
};
const ObjectShape& ShapeOf(ObjectKind kind);

struct MapObject {
  ObjectKind kind = ObjectKind::kHouse;
  Eigen::Vector2d position{0, 0};  // centre of the footprint, world metres
  double rotation_deg = 0.0;       // about z, counter-clockwise from east
};

// A path through the road graph as the tiles it drives through, in driving
// order. A closed route's last tile joins its first (not repeated).
struct Route {
  std::string name;
  bool closed = true;
  std::vector<TileCoord> tiles;
};

struct Map {
  std::string name;
  double tile_size = 20.0;  // metres
  Surroundings surroundings = Surroundings::kDesert;
  int width = 0, height = 0;   // tiles
  std::vector<EdgeMask> road;  // width * height connection masks, row-major, row 0 north; 0 = no road
  std::vector<MapObject> objects;
  std::vector<Route> routes;

  bool InGrid(TileCoord t) const { return t.col >= 0 && t.row >= 0 && t.col < width && t.row < height; }
  // 0 outside the grid.
  EdgeMask ConnectionsAt(TileCoord t) const { return InGrid(t) ? road[Index(t)] : 0; }
  TileKind KindAt(TileCoord t) const { return KindOf(ConnectionsAt(t)); }
  std::size_t Index(TileCoord t) const { return static_cast<std::size_t>(t.row) * width + t.col; }
  TileCoord CoordOf(std::size_t index) const {
    return {static_cast<int>(index % width), static_cast<int>(index / width)};
  }

  // The grid is centred on the world origin: it covers
  // [-width*tile_size/2, +width*tile_size/2] in x and likewise in y.
  Eigen::Vector2d TileCentre(TileCoord t) const;
  // The tile containing world point `p` (possibly outside the grid).
  TileCoord TileAt(const Eigen::Vector2d& p) const;
  Eigen::Vector2d HalfExtent() const { return {width * tile_size / 2, height * tile_size / 2}; }

  const Route* FindRoute(const std::string& route_name) const;
};

// Centre-line length of one road tile: straight T, curve pi*T/4 (a quarter
// circle of radius T/2), T-junction 1.5*T, crossroads 2*T, dead end T/2.
double TileRoadLength(TileKind kind, double tile_size);
// Sum over all road tiles: the "road length" of a map.
double RoadLength(const Map& map);

// Groups of 4-connected road tiles linked by their connections; a usable
// map has exactly one.
int CountRoadComponents(const Map& map);

}  // namespace sim4cv::map
