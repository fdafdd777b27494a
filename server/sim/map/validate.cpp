#include "server/sim/map/validate.h"

#include <sstream>

namespace sim4cv::map {

bool ClearOfRoad(const RoadGraph& graph, const Eigen::Vector2d& p, double radius, double clearance) {
  if (graph.segments().empty()) return true;
  // The road surface is every point within half a lane of some lane centre.
  return graph.Nearest(p).distance >= kLaneWidth / 2 + radius + clearance;
}

std::vector<std::string> FindProblems(const Map& map, const RoadGraph& graph) {
  std::vector<std::string> problems;
  if (graph.segments().empty()) problems.push_back("the map has no road");
  const int components = CountRoadComponents(map);
  if (components > 1) {
    std::ostringstream why;
    why << "the road is " << components << " separate networks, not one";
    problems.push_back(why.str());
  }
  for (std::size_t i = 0; i < map.objects.size(); ++i) {
    const MapObject& object = map.objects[i];
    if (object.kind == ObjectKind::kObstacle) continue;  // obstacles are there to be driven around
    if (ClearOfRoad(graph, object.position, ShapeOf(object.kind).base_radius)) continue;
    std::ostringstream why;
    why << "object " << i << " (" << ObjectKindName(object.kind) << " at " << object.position.x() << " "
        << object.position.y() << ") stands on the road";
    problems.push_back(why.str());
  }
  return problems;
}

}  // namespace sim4cv::map
