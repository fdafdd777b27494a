// Laying out what stands beside and on the lanes: parked cars at the kerb,
// the places moving cars may start from, and map objects that block a lane
// (docs/maps.md, "Traffic").
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>

#include "server/sim/map/validate.h"
#include "server/sim/traffic/layout_util.h"
#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::traffic {
namespace {

// Between a parked car and objects, light poles, crosswalks and other parked cars.
constexpr double kParkedClearance = 0.3;
// Bumper to bumper between neighbouring kerb slots.
constexpr double kParkedGap = 1.5;
// A parked car's body keeps this far off every lane's centre: half a lane
// (the road surface) and 0.2 m more.
constexpr double kOffRoad = map::kLaneWidth / 2 + 0.2;
// A moving car does not start within this of a crosswalk or an object on the road.
constexpr double kStartClearance = 1.0;

// Where walkers go: the walking line with room for a body either side.
Box2 WalkBox(const TrafficPlan::WalkPath& path) {
  return {(path.start + path.end) / 2, layout::HeadingOf(path.end - path.start), path.length / 2 + kWalkerRadius,
          kWalkerRadius};
}

Box2 CarBox(const Eigen::Vector2d& centre, double heading) { return {centre, heading, kCarLength / 2, kCarWidth / 2}; }

// Distance from p to the nearest lane centre among the segments of `tile`
// and its eight neighbours (nothing further can be nearer than they are).
double LaneDistanceNear(const map::RoadGraph& graph, const map::TileCoord& tile, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const map::LaneSegment& segment : graph.segments()) {
    if (std::abs(segment.tile.col - tile.col) > 1 || std::abs(segment.tile.row - tile.row) > 1) continue;
    best = std::min(best, segment.curve.Project(p).distance);
  }
  return best;
}

}  // namespace

void TrafficPlan::FindRoadObstacles(const map::Map& map) {
  for (const map::MapObject& object : map.objects) {
    const double radius = map::ShapeOf(object.kind).base_radius;
    if (!map::ClearOfRoad(graph_, object.position, radius)) road_obstacles_.push_back({object.position, radius});
  }
}

std::vector<Pose2> TrafficPlan::FindKerbSlots(const map::Map& map) const {
  std::vector<Box2> keep_out;
  for (const WalkPath& path : walk_paths_) keep_out.push_back(WalkBox(path));
  for (const Light& light : lights_) keep_out.push_back({light.position, 0.0, 0.3, 0.3});
  const double pitch = kCarLength + kParkedGap;
  const int per_side = static_cast<int>(std::floor((map.tile_size - kParkedGap) / pitch));
  std::vector<Pose2> slots;
  std::vector<Box2> taken;
  for (std::size_t i = 0; i < map.road.size(); ++i) {
    const map::TileCoord tile = map.CoordOf(i);
    if (map.KindAt(tile) != map::TileKind::kStraight) continue;  // never on junctions or in bends
    const Eigen::Vector2d axis =
        map::Has(map.road[i], map::Edge::kNorth) ? Eigen::Vector2d(0, 1) : Eigen::Vector2d(1, 0);
    for (const Eigen::Vector2d& forward : {axis, Eigen::Vector2d(-axis)}) {
      // At the kerb on the right of the lane running `forward`, facing along it.
      for (int k = 0; k < per_side; ++k) {
        const double offset = (k - (per_side - 1) / 2.0) * pitch;
        const Box2 box = CarBox(map.TileCentre(tile) + forward * offset + layout::RightOf(forward) * kParkedLateral,
                                layout::HeadingOf(forward));
        const Box2 grown = Grown(box, kParkedClearance);
        const auto overlaps = [&](const Box2& other) { return Overlap(grown, other); };
        if (!layout::ClearOfObjects(map, box, kParkedClearance)) continue;
        if (std::any_of(keep_out.begin(), keep_out.end(), overlaps)) continue;
        if (std::any_of(taken.begin(), taken.end(), overlaps)) continue;
        // Off the road surface everywhere, not only beside its own lane (a
        // street running alongside, a bend in the next tile).
        const std::array<Eigen::Vector2d, 4> corners = Corners(box);
        const bool off_road = std::all_of(corners.begin(), corners.end(), [&](const Eigen::Vector2d& corner) {
          return LaneDistanceNear(graph_, tile, corner) >= kOffRoad;
        });
        if (!off_road) continue;
        slots.push_back({box.centre, box.heading});
        taken.push_back(box);
      }
    }
  }
  return slots;
}

std::vector<map::LanePoint> TrafficPlan::FindStartSlots() const {
  std::vector<Box2> keep_out;
  for (const WalkPath& path : walk_paths_) keep_out.push_back(Grown(WalkBox(path), kStartClearance));
  for (const RoadObstacle& obstacle : road_obstacles_) {
    keep_out.push_back({obstacle.position, 0.0, obstacle.radius + kStartClearance, obstacle.radius + kStartClearance});
  }
  // Every metre along every lane outside junctions and dead ends, first come
  // first served in segment order, kept only if it is kStartSpacing from
  // every slot already taken that runs the same way (the oncoming lane, 4 m
  // off, does not count).
  std::vector<map::LanePoint> slots;
  for (const map::LaneSegment& segment : graph_.segments()) {
    if (JunctionOf(segment.id) >= 0 || segment.turn == map::Turn::kUTurn) continue;
    const bool junction_next = !segment.successors.empty() && JunctionOf(segment.successors.front()) >= 0;
    for (double s = 0.5; s < segment.length(); s += 1.0) {
      // Not between the stop line and the junction, where a red light would find it.
      if (junction_next && segment.length() - s < kStopLineBack + kCarLength / 2 + 0.5) continue;
      const map::LanePoint at = graph_.At(segment.id, s);
      const Box2 box = CarBox(at.position, at.heading);
      if (std::any_of(keep_out.begin(), keep_out.end(), [&](const Box2& k) { return Overlap(box, k); })) continue;
      const bool spaced = std::all_of(slots.begin(), slots.end(), [&](const map::LanePoint& other) {
        return std::abs(map::WrapAngle(other.heading - at.heading)) >= std::numbers::pi / 2 ||
               (other.position - at.position).norm() >= kStartSpacing;
      });
      if (spaced) slots.push_back(at);
    }
  }
  return slots;
}

}  // namespace sim4cv::traffic
