// Dressing a road network with objects (docs/maps.md, "Generating maps").
//
// Two passes, both in a fixed order so a seed always gives the same map:
// 1. Roadside slots, one per side of the road about every 10 m beside
//    straights and curves (never in junctions, where they would block the
//    view of crossing traffic): lanterns and trees just off the road edge.
// 2. Blocks: every empty tile is cut into cells of about 20 m; each cell
//    gets a house, a park, a few trees, a rock or nothing, by surroundings.
// An object goes down only where its base clears the road and every object
// already placed; one that does not fit is skipped (houses and parks fall
// back to trees).
#include <cmath>
#include <numbers>

#include "server/sim/map/generator.h"
#include "server/sim/map/prng.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/map/validate.h"

namespace sim4cv::map {
namespace {

constexpr double kClearance = 0.5;            // m between objects, and between an object and the road edge
constexpr double kCellSize = 20.0;            // m, about; a cell holds one house or park
constexpr double kRoadsideSpacing = 10.0;     // m between roadside slots along a lane
constexpr double kLanternChance = 0.3;        // per roadside slot, urban only
constexpr double kUrbanRoadsideTrees = 0.15;  // default roadside-tree chances
constexpr double kDesertRoadsideTrees = 0.0;
constexpr double kRoadsideSlack = 0.1;  // m beyond the clearance, so rounding to 0.01 m cannot push it onto the road
constexpr uint64_t kDressingStream = 0xD2E5'51A6'E0F5'EED0ull;  // keeps dressing draws apart from the roads'

double Round2(double value) { return std::round(value * 100) / 100; }

class Placer {
 public:
  Placer(Map& map, const RoadGraph& graph) : map_(map), graph_(graph) {}

  bool TryPlace(ObjectKind kind, const Eigen::Vector2d& at, double rotation_deg) {
    // Round first, so what is checked is what the text will say.
    const Eigen::Vector2d p(Round2(at.x()), Round2(at.y()));
    const double r = ShapeOf(kind).base_radius;
    const Eigen::Vector2d half = map_.HalfExtent();
    if (std::abs(p.x()) > half.x() - r || std::abs(p.y()) > half.y() - r) return false;
    for (const MapObject& other : map_.objects) {
      if ((other.position - p).norm() < r + ShapeOf(other.kind).base_radius + kClearance) return false;
    }
    if (!ClearOfRoad(graph_, p, r, kClearance)) return false;
    double rotation = std::fmod(rotation_deg, 360.0);
    if (rotation < 0) rotation += 360.0;
    map_.objects.push_back({kind, p, Round2(rotation)});
    return true;
  }

 private:
  Map& map_;
  const RoadGraph& graph_;
};

void DressRoadside(const RoadGraph& graph, const Map& map, Prng& rng, Placer& placer, double tree_chance) {
  const bool urban = map.surroundings == Surroundings::kUrban;
  for (const LaneSegment& segment : graph.segments()) {
    const TileKind kind = map.KindAt(segment.tile);
    if (kind != TileKind::kStraight && kind != TileKind::kCurve) continue;
    const double length = segment.length();
    const int slots = std::max(1, static_cast<int>(std::lround(length / kRoadsideSpacing)));
    for (int k = 0; k < slots; ++k) {
      // Each lane dresses its own right-hand side, so both sides get slots.
      const LanePoint at = graph.At(segment.id, (k + 0.5) * length / slots);
      const Eigen::Vector2d right(std::sin(at.heading), -std::cos(at.heading));
      const double heading_deg = at.heading * 180.0 / std::numbers::pi;
      const auto off_road = [&](ObjectKind object) {
        return at.position + right * (kLaneWidth / 2 + kClearance + kRoadsideSlack + ShapeOf(object).base_radius);
      };
      const double u = rng.Uniform();
      if (urban && u < kLanternChance) {
        placer.TryPlace(ObjectKind::kLantern, off_road(ObjectKind::kLantern), heading_deg);
      } else if (rng.Chance(tree_chance)) {
        placer.TryPlace(ObjectKind::kTree, off_road(ObjectKind::kTree), rng.Uniform(0, 360));
      }
    }
  }
}

void PlaceTrees(Prng& rng, Placer& placer, const Eigen::Vector2d& centre, double cell, int count) {
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d jitter(rng.Uniform(-cell / 2, cell / 2), rng.Uniform(-cell / 2, cell / 2));
    placer.TryPlace(ObjectKind::kTree, centre + jitter, rng.Uniform(0, 360));
  }
}

void DressCell(const Map& map, Prng& rng, Placer& placer, const Eigen::Vector2d& centre, double cell) {
  const double u = rng.Uniform();
  if (map.surroundings == Surroundings::kDesert) {
    // Sand with the odd tree and rock.
    if (u < 0.04) placer.TryPlace(ObjectKind::kTree, centre, rng.Uniform(0, 360));
    if (u >= 0.04 && u < 0.08) placer.TryPlace(ObjectKind::kObstacle, centre, rng.Uniform(0, 360));
    return;
  }
  if (u < 0.5) {
    // A house turned by a multiple of 90 degrees, nudged a little off centre.
    for (int attempt = 0; attempt < 4; ++attempt) {
      const Eigen::Vector2d jitter(rng.Uniform(-1.5, 1.5), rng.Uniform(-1.5, 1.5));
      if (placer.TryPlace(ObjectKind::kHouse, centre + jitter, 90.0 * rng.UniformInt(0, 3))) return;
    }
    PlaceTrees(rng, placer, centre, cell, 2);
  } else if (u < 0.6) {
    if (!placer.TryPlace(ObjectKind::kPark, centre, 0.0)) PlaceTrees(rng, placer, centre, cell, 2);
  } else if (u < 0.85) {
    PlaceTrees(rng, placer, centre, cell, rng.UniformInt(1, 3));
  }
}

}  // namespace

void Dress(Map& map, uint64_t seed, double roadside_trees) {
  const RoadGraph graph(map);
  uint64_t stream = seed ^ kDressingStream;
  Prng rng(SplitMix64(stream));
  Placer placer(map, graph);
  const bool urban = map.surroundings == Surroundings::kUrban;
  DressRoadside(graph, map, rng, placer,
                roadside_trees >= 0 ? roadside_trees : (urban ? kUrbanRoadsideTrees : kDesertRoadsideTrees));
  const int cells = std::max(1, static_cast<int>(std::lround(map.tile_size / kCellSize)));
  const double cell = map.tile_size / cells;
  for (std::size_t i = 0; i < map.road.size(); ++i) {
    if (map.road[i] != 0) continue;
    const Eigen::Vector2d corner = map.TileCentre(map.CoordOf(i)) - Eigen::Vector2d(map.tile_size, map.tile_size) / 2;
    for (int cy = 0; cy < cells; ++cy) {
      for (int cx = 0; cx < cells; ++cx) {
        DressCell(map, rng, placer, corner + Eigen::Vector2d((cx + 0.5) * cell, (cy + 0.5) * cell), cell);
      }
    }
  }
}

}  // namespace sim4cv::map
