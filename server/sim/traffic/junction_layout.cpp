// Laying out junctions: their cycles, one light per arm, which of their
// lanes cross, and the crosswalks (docs/maps.md, "Traffic").
#include <algorithm>
#include <cmath>
#include <limits>

#include "server/common/check.h"
#include "server/sim/map/validate.h"
#include "server/sim/traffic/layout_util.h"
#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::traffic {
namespace {

using map::Edge;
using map::SegmentId;
using map::TileKind;

// Lanes this close somewhere can carry cars that touch: two 1.8 m bodies
// with room for the corners a 4.5 m car sweeps out on an arc. Lanes running
// side by side (4 m apart) stay apart.
constexpr double kConflictDistance = 3.0;
// A light's pole and housing, as a disc, and what it keeps off objects and the road.
constexpr double kLightRadius = 0.3;
constexpr double kLightClearance = 0.4;
// What a walker at the end of its path keeps off objects and lights.
constexpr double kWalkerClearance = kWalkerRadius + 0.2;
// A walking line never ends closer to the road's centre line than this (the
// road edge is at 4 m).
constexpr double kMinReach = map::kLaneWidth + 0.2;

bool IsJunction(TileKind kind) { return kind == TileKind::kTJunction || kind == TileKind::kCrossroads; }

double MinDistance(const map::LaneCurve& a, const map::LaneCurve& b) {
  const int samples = static_cast<int>(std::ceil(a.length() / 0.25));
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= samples; ++k) best = std::min(best, b.Project(a.PointAt(a.length() * k / samples)).distance);
  return best;
}

}  // namespace

void TrafficPlan::PlaceJunctions(const map::Map& map, map::Prng& rng) {
  const std::vector<map::LaneSegment>& segments = graph_.segments();
  const std::size_t n = segments.size();
  light_of_segment_.assign(n, -1);
  junction_of_segment_.assign(n, -1);
  first_in_tile_.assign(n, -1);
  conflicts_.assign(n, 0);
  std::vector<SegmentId> tile_segments;
  // The graph numbers segments tile by tile, so a tile's segments are a run of ids.
  for (std::size_t first = 0; first < n;) {
    const map::TileCoord tile = segments[first].tile;
    tile_segments.clear();
    for (std::size_t id = first; id < n && segments[id].tile == tile; ++id) {
      tile_segments.push_back(static_cast<SegmentId>(id));
      first_in_tile_[id] = static_cast<SegmentId>(first);
    }
    first += tile_segments.size();
    if (!IsJunction(map.KindAt(tile))) continue;
    SIM4CV_DEMAND(tile_segments.size() <= 16);  // a crossroads has 12
    const int junction = static_cast<int>(junctions_.size());
    junctions_.push_back({tile, rng.Uniform(0, cycle_s())});
    for (SegmentId id : tile_segments) junction_of_segment_[id] = junction;
    if (config_.traffic_lights) {
      for (Edge entry : map::kEdges) {
        if (!map::Has(map.ConnectionsAt(tile), entry)) continue;
        const int light = static_cast<int>(lights_.size());
        lights_.push_back(MakeLight(map, junction, entry));
        for (SegmentId id : tile_segments) {
          if (segments[id].entry == entry) light_of_segment_[id] = light;
        }
      }
    }
    FindConflicts(tile_segments);
  }
}

TrafficPlan::Light TrafficPlan::MakeLight(const map::Map& map, int junction, Edge entry) const {
  const map::TileCoord tile = junctions_[junction].tile;
  const Eigen::Vector2d out = map::Outward(entry);  // along the arm, away from the junction
  const Eigen::Vector2d edge_middle = map.TileCentre(tile) + out * (map.tile_size / 2);
  const Eigen::Vector2d right = layout::RightOf(-out);  // of the traffic coming in
  Light light;
  light.junction = junction;
  light.entry = entry;
  light.axis = (entry == Edge::kNorth || entry == Edge::kSouth) ? 0 : 1;
  light.heading = layout::HeadingOf(out);
  const auto at = [&](double back) { return Eigen::Vector2d(edge_middle + out * back + right * kLightLateral); };
  // Level with the stop line, unless a roadside lantern or tree stands
  // there (the generator puts them about every 10 m): then a little further
  // back, or just in front of the stop line.
  light.position = at(kLightBack);
  for (double back : {kLightBack, kLightBack + 1, kLightBack + 2, kLightBack + 3, kLightBack - 0.8}) {
    if (layout::ClearOfObjects(map, at(back), kLightRadius + kLightClearance) &&
        map::ClearOfRoad(graph_, at(back), kLightRadius, kLightClearance)) {
      light.position = at(back);
      break;
    }
  }
  if (const std::optional<SegmentId> straight = graph_.Find(tile, entry, map::Opposite(entry))) {
    light.controls = *straight;
  } else {
    for (Edge exit : map::kEdges) {
      if (const std::optional<SegmentId> id = graph_.Find(tile, entry, exit); id && light.controls < 0) {
        light.controls = *id;
      }
    }
  }
  return light;
}

void TrafficPlan::FindConflicts(const std::vector<SegmentId>& tile_segments) {
  const std::vector<map::LaneSegment>& segments = graph_.segments();
  for (SegmentId a : tile_segments) {
    for (SegmentId b : tile_segments) {
      // Cars from the same side are in one queue: following, not crossing.
      if (b <= a || segments[a].entry == segments[b].entry) continue;
      if (MinDistance(segments[a].curve, segments[b].curve) >= kConflictDistance) continue;
      conflicts_[a] |= static_cast<uint16_t>(1u << (b - first_in_tile_[a]));
      conflicts_[b] |= static_cast<uint16_t>(1u << (a - first_in_tile_[b]));
    }
  }
}

bool TrafficPlan::Conflict(SegmentId a, SegmentId b) const {
  const int junction = junction_of_segment_[a];
  if (junction < 0 || junction != junction_of_segment_[b]) return false;
  return ((conflicts_[a] >> (b - first_in_tile_[a])) & 1u) != 0;
}

void TrafficPlan::PlaceCrosswalks(const map::Map& map) {
  if (!junctions_.empty()) {
    // Across every arm of every junction, between the stop line and the junction.
    for (std::size_t j = 0; j < junctions_.size(); ++j) {
      const map::TileCoord tile = junctions_[j].tile;
      for (Edge entry : map::kEdges) {
        if (!map::Has(map.ConnectionsAt(tile), entry)) continue;
        int light = -1;
        for (std::size_t l = 0; l < lights_.size(); ++l) {
          if (lights_[l].junction == static_cast<int>(j) && lights_[l].entry == entry) light = static_cast<int>(l);
        }
        const Eigen::Vector2d out = map::Outward(entry);
        const Eigen::Vector2d middle = map.TileCentre(tile) + out * (map.tile_size / 2 + kCrosswalkBack);
        AddCrosswalk(map, middle, layout::RightOf(-out), out, light);
      }
    }
    return;
  }
  // No junctions: across the middle of every straight, nudged along it where
  // an object stands at the pavement end.
  for (std::size_t i = 0; i < map.road.size(); ++i) {
    const map::TileCoord tile = map.CoordOf(i);
    if (map.KindAt(tile) != TileKind::kStraight) continue;
    const Eigen::Vector2d along = map::Has(map.road[i], Edge::kNorth) ? Eigen::Vector2d(0, 1) : Eigen::Vector2d(1, 0);
    const Eigen::Vector2d across = layout::RightOf(along);
    const auto ends_clear = [&](const Eigen::Vector2d& middle) {
      for (double side : {-1.0, 1.0}) {
        for (double end : {-1.0, 1.0}) {
          const Eigen::Vector2d p = middle + along * side * kCrosswalkHalfWidth + across * end * kCrosswalkReach;
          if (!layout::ClearOfObjects(map, p, kWalkerClearance)) return false;
        }
      }
      return true;
    };
    Eigen::Vector2d middle = map.TileCentre(tile);
    for (double shift : {0.0, 1.5, -1.5, 3.0, -3.0}) {
      if (ends_clear(map.TileCentre(tile) + along * shift)) {
        middle = map.TileCentre(tile) + along * shift;
        break;
      }
    }
    AddCrosswalk(map, middle, across, along, -1);
  }
}

void TrafficPlan::AddCrosswalk(const map::Map& map, const Eigen::Vector2d& middle, const Eigen::Vector2d& across,
                               const Eigen::Vector2d& along, int light) {
  // How far a walking line may reach from `line` towards `direction` before
  // a walker standing at its end would touch an object or a light pole.
  const auto reach = [&](const Eigen::Vector2d& line, const Eigen::Vector2d& direction) {
    for (int tenths = static_cast<int>(std::lround(kCrosswalkReach * 10)); tenths >= kMinReach * 10; --tenths) {
      const Eigen::Vector2d end = line + direction * (tenths / 10.0);
      const bool clear_of_lights = std::all_of(lights_.begin(), lights_.end(), [&](const Light& l) {
        return (l.position - end).norm() >= kLightRadius + kWalkerClearance;
      });
      if (clear_of_lights && layout::ClearOfObjects(map, end, kWalkerClearance)) return tenths / 10.0;
    }
    return kMinReach;
  };
  crosswalks_.push_back({middle, across.normalized(), along.normalized()});
  // Lines side by side across the crosswalk, walked from alternate
  // pavements, so walkers on one crosswalk pass without meeting.
  for (int line = 0; line < kWalkLines; ++line) {
    const Eigen::Vector2d on_line = middle + along * ((line - (kWalkLines - 1) / 2.0) * kWalkLineSpacing);
    const Eigen::Vector2d from = line % 2 == 0 ? Eigen::Vector2d(-across) : across;
    WalkPath path;
    path.start = on_line + from * reach(on_line, from);
    path.end = on_line - from * reach(on_line, -from);
    path.length = (path.end - path.start).norm();
    path.light = light;
    path.crossings = FindCrossings(path.start, path.end);
    walk_paths_.push_back(path);
  }
}

std::vector<TrafficPlan::LaneCrossing> TrafficPlan::FindCrossings(const Eigen::Vector2d& start,
                                                                  const Eigen::Vector2d& end) const {
  const double length = (end - start).norm();
  const Eigen::Vector2d unit = (end - start) / length;
  // Signed distance from the walking line's carrier, and whether the foot of
  // the perpendicular falls on the line itself.
  const auto side = [&](const Eigen::Vector2d& p) {
    return unit.x() * (p.y() - start.y()) - unit.y() * (p.x() - start.x());
  };
  const auto within = [&](const Eigen::Vector2d& p) {
    const double along = (p - start).dot(unit);
    return along >= 0 && along <= length;
  };
  std::vector<LaneCrossing> crossings;
  constexpr double kStep = 0.25;
  for (const map::LaneSegment& segment : graph_.segments()) {
    const map::LaneCurve& curve = segment.curve;
    // Every point of a curve lies within its length of its start: a cheap
    // test that skips the far segments before the exact one (trigonometry),
    // so a large map's plan is not dominated by this loop (docs/reliability.md, finding 2).
    const Eigen::Vector2d mid = (start + end) / 2;
    if ((curve.pieces().front().start - mid).norm() - curve.length() > length + 1.0) continue;
    if (curve.Project(mid).distance > length + 1.0) continue;  // nowhere near
    const int samples = static_cast<int>(std::ceil(curve.length() / kStep));
    for (int k = 0; k < samples; ++k) {
      double lo = curve.length() * k / samples, hi = curve.length() * (k + 1) / samples;
      if ((side(curve.PointAt(lo)) < 0) == (side(curve.PointAt(hi)) < 0)) continue;
      for (int i = 0; i < 40; ++i) {  // bisection to well below a millimetre
        const double mid = (lo + hi) / 2;
        ((side(curve.PointAt(mid)) < 0) == (side(curve.PointAt(lo)) < 0) ? lo : hi) = mid;
      }
      const Eigen::Vector2d at = curve.PointAt(lo);
      if (within(at)) crossings.push_back({segment.id, lo, (at - start).dot(unit)});
    }
  }
  return crossings;
}

}  // namespace sim4cv::traffic
