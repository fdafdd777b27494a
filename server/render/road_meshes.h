// The road surface of one map tile, built from the road graph's exact lane
// geometry so what is drawn is what cars drive: asphalt, a dashed centre
// line, solid edge lines, and by surroundings either sidewalks with curbs and
// crosswalks at junctions (urban) or gravel shoulders (desert).
#pragma once

#include "server/render/render_types.h"
#include "server/sim/map/map.h"
#include "server/sim/map/road_graph.h"

namespace sim4cv::render {

// Heights above the ground (z = 0). Each layer clears the one below by at
// least 2 cm: with a 0.1 m near plane and a 24-bit depth buffer, depth steps
// are about 6 mm at 100 m, so the layers never fight at the distances the
// cameras use.
inline constexpr float kShoulderHeight = 0.02f;
inline constexpr float kAsphaltHeight = 0.04f;
inline constexpr float kMarkingHeight = 0.07f;
inline constexpr float kSidewalkHeight = 0.15f;

// Appends road tile `tile`'s surface, in world coordinates, to `mesh`.
// Neighbouring tiles meet exactly (the same points along each tile side).
void AppendRoadTile(Mesh& mesh, const map::Map& map, const map::RoadGraph& graph, map::TileCoord tile);

}  // namespace sim4cv::render
