// Everything static a tile map shows, as meshes the Renderer can draw: the
// ground, the road network and one labelled mesh per dressing object.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "server/render/render_types.h"
#include "server/sim/map/map.h"
#include "server/sim/map/road_graph.h"

namespace sim4cv::render {

struct MapDrawable {
  Mesh mesh;
  Eigen::Matrix4f world_from_model = Eigen::Matrix4f::Identity();
  InstanceId instance = kUnlabelled;
  uint32_t object_class = 0;  // proto ObjectClass; 0 for the unlabelled ground and road
};

// First the unlabelled geometry: ground and road merged into square chunks
// of about 60 m (world coordinates, identity pose; separate chunks let the
// renderer's frustum culling skip what a low camera cannot see), then one
// skirt of ground out to 2 km so a level camera sees no sky below the
// horizon. Then one drawable per map object, in map order, with instance ids
// first_instance, first_instance + 1, ... and classes house BUILDING, tree
// TREE, lantern LANTERN, obstacle OBSTACLE, park PARK; each mesh is in the
// object's own frame (see MakeObjectMesh) and world_from_model is its pose.
// `graph` must be built from `map`. Throws std::invalid_argument if the ids
// would not fit 1..65535.
std::vector<MapDrawable> BuildMapDrawables(const map::Map& map, const map::RoadGraph& graph, InstanceId first_instance);

}  // namespace sim4cv::render
