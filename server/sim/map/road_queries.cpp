// Queries on the lane graph: nearest lane, points ahead, routes.
#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <numbers>

#include "server/common/check.h"
#include "server/sim/map/road_graph.h"

namespace sim4cv::map {

namespace {

// The nearest lane point to `p` among the segments `visit` hands to its
// callback; with `heading`, lanes running 90 degrees or more away from it
// are skipped unless no lane is left. The lateral offset is set too.
template <typename Visit>
LaneProjection NearestAmong(const Eigen::Vector2d& p, std::optional<double> heading, const Visit& visit) {
  const auto search = [&](bool filter) {
    LaneProjection best;
    best.distance = std::numeric_limits<double>::infinity();
    visit([&](const LaneSegment& segment) {
      const LaneCurve::Nearest nearest = segment.curve.Project(p);
      if (nearest.distance >= best.distance) return;
      const double lane_heading = segment.curve.HeadingAt(nearest.s);
      if (filter && std::abs(WrapAngle(lane_heading - *heading)) >= std::numbers::pi / 2) return;
      best.lane = {segment.id, nearest.s, segment.curve.PointAt(nearest.s), lane_heading};
      best.distance = nearest.distance;
    });
    return best;
  };
  LaneProjection best = search(heading.has_value());
  if (best.lane.segment < 0) best = search(false);
  const Eigen::Vector2d forward(std::cos(best.lane.heading), std::sin(best.lane.heading));
  const Eigen::Vector2d offset = p - best.lane.position;
  best.lateral_offset = forward.x() * offset.y() - forward.y() * offset.x();
  return best;
}

}  // namespace

LaneProjection RoadGraph::Nearest(const Eigen::Vector2d& p, std::optional<double> heading) const {
  SIM4CV_THROW_UNLESS(!segments_.empty(), "the map has no road");
  // Every segment is searched: maps hold at most a few thousand, and the
  // answer stays exact wherever p is (even off the grid).
  return NearestAmong(p, heading, [&](const auto& take) {
    for (const LaneSegment& segment : segments_) take(segment);
  });
}

LaneProjection RoadGraph::NearestOnRoute(const Eigen::Vector2d& p, std::span<const SegmentId> route) const {
  SIM4CV_THROW_UNLESS(!route.empty(), "the route has no lane segments");
  return NearestAmong(p, std::nullopt, [&](const auto& take) {
    for (SegmentId id : route) take(segment(id));
  });
}

std::vector<LanePoint> RoadGraph::PointsAlongRoute(const LanePoint& from, double step, int count,
                                                   std::span<const SegmentId> route) const {
  const JunctionChooser follow = [&](const LaneSegment& current, std::span<const SegmentId> options) {
    const auto at = std::find(route.begin(), route.end(), current.id);
    if (at != route.end()) {
      const auto next = std::next(at) != route.end() ? *std::next(at) : route.front();  // a closed route wraps
      const auto wanted = std::find(options.begin(), options.end(), next);
      if (wanted != options.end()) return static_cast<std::size_t>(wanted - options.begin());
    }
    return ChooseTurn(options, Turn::kStraight);
  };
  return PointsAhead(from, step, count, follow);
}

LanePoint RoadGraph::Advance(const LanePoint& from, double distance, const JunctionChooser& choose) const {
  SIM4CV_THROW_UNLESS(distance >= 0 && std::isfinite(distance), "cannot advance " << distance << " m");
  SegmentId id = segment(from.segment).id;
  double s = std::clamp(from.s, 0.0, segments_[id].length()) + distance;
  while (s > segments_[id].length()) {
    s -= segments_[id].length();
    const LaneSegment& current = segments_[id];
    // Every segment leaves into a road tile, and every road tile has a lane
    // in from each connected side, so there is always a successor.
    SIM4CV_DEMAND(!current.successors.empty());
    std::size_t pick = 0;
    if (current.successors.size() > 1) {
      pick = choose(current, current.successors);
      SIM4CV_THROW_UNLESS(pick < current.successors.size(),
                          "junction choice " << pick << " of " << current.successors.size() << " options");
    }
    id = current.successors[pick];
  }
  return At(id, s);
}

std::vector<LanePoint> RoadGraph::PointsAhead(const LanePoint& from, double step, int count,
                                              const JunctionChooser& choose) const {
  SIM4CV_THROW_UNLESS(step > 0 && count >= 0,
                      "points ahead need step > 0 and count >= 0, not " << step << ", " << count);
  std::vector<LanePoint> points;
  points.reserve(count);
  LanePoint at = from;
  for (int i = 0; i < count; ++i) {
    at = Advance(at, step, choose);
    points.push_back(at);
  }
  return points;
}

std::vector<LanePoint> RoadGraph::PointsAhead(const LanePoint& from, double step, int count,
                                              std::span<const Turn> turns) const {
  std::size_t next_turn = 0;
  const JunctionChooser follow = [&](const LaneSegment&, std::span<const SegmentId> options) {
    const Turn wanted = next_turn < turns.size() ? turns[next_turn] : Turn::kStraight;
    ++next_turn;
    return ChooseTurn(options, wanted);
  };
  return PointsAhead(from, step, count, follow);
}

std::size_t RoadGraph::ChooseTurn(std::span<const SegmentId> options, Turn wanted) const {
  SIM4CV_THROW_UNLESS(!options.empty(), "no options to choose from");
  for (Turn turn : {wanted, Turn::kStraight, Turn::kRight, Turn::kLeft, Turn::kUTurn}) {
    for (std::size_t i = 0; i < options.size(); ++i) {
      if (segment(options[i]).turn == turn) return i;
    }
  }
  return 0;
}

std::vector<SegmentId> RoadGraph::RouteSegments(const Route& route) const {
  const std::size_t n = route.tiles.size();
  SIM4CV_THROW_UNLESS(n >= (route.closed ? 2u : 3u), "route '" << route.name << "' is too short (" << n << " tiles)");
  std::vector<SegmentId> ids;
  const std::size_t first = route.closed ? 0 : 1;
  const std::size_t last = route.closed ? n : n - 1;  // one past
  for (std::size_t i = first; i < last; ++i) {
    const TileCoord at = route.tiles[i];
    const TileCoord before = route.tiles[(i + n - 1) % n];
    const TileCoord after = route.tiles[(i + 1) % n];
    Edge entry{}, exit{};
    std::optional<SegmentId> id;
    if (EdgeTowards(at, before, &entry) && EdgeTowards(at, after, &exit)) id = Find(at, entry, exit);
    SIM4CV_THROW_UNLESS(id.has_value(), "route '" << route.name << "' cannot pass tile " << at.col << "," << at.row);
    ids.push_back(*id);
  }
  return ids;
}

SampledPath RoadGraph::SampleRoute(const Route& route, double spacing) const {
  SIM4CV_THROW_UNLESS(spacing > 0, "sample spacing " << spacing << " must be > 0");
  SampledPath path;
  path.closed = route.closed;
  // Samples `curve` at `s`; path.length is where the curve starts.
  const auto add = [&](const LaneCurve& curve, double s) {
    path.points.push_back(curve.PointAt(s));
    path.heading.push_back(curve.HeadingAt(s));
    path.arc_length.push_back(path.length + s);
  };
  const std::vector<SegmentId> ids = RouteSegments(route);
  for (SegmentId id : ids) {
    const LaneCurve& curve = segments_[id].curve;
    const int parts = std::max(1, static_cast<int>(std::ceil(curve.length() / spacing - 1e-9)));
    for (int k = 0; k < parts; ++k) add(curve, curve.length() * k / parts);
    path.length += curve.length();
  }
  if (!route.closed) {
    const LaneCurve& curve = segments_[ids.back()].curve;
    path.length -= curve.length();
    add(curve, curve.length());  // the end of an open path is a sample too
    path.length += curve.length();
  }
  return path;
}

}  // namespace sim4cv::map
