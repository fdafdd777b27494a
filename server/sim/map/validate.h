// What makes a map that parses unfit to drive on (sim4cv_maptool check).
#pragma once

#include <string>
#include <vector>

#include "server/sim/map/map.h"
#include "server/sim/map/road_graph.h"

namespace sim4cv::map {

// One line per problem; empty when the map is fit: it has road, all of it
// one connected network, and no object except obstacles stands on the road
// (a tree's trunk must not, its crown may overhang).
std::vector<std::string> FindProblems(const Map& map, const RoadGraph& graph);

// Whether a disc of `radius` around `p` keeps `clearance` metres off the road surface.
bool ClearOfRoad(const RoadGraph& graph, const Eigen::Vector2d& p, double radius, double clearance = 0.0);

}  // namespace sim4cv::map
