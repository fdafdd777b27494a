// Meshes of the map's dressing objects, sized by map::ShapeOf so graphics
// and physics agree: houses, trees, lanterns, parks, obstacles.
#pragma once

#include <Eigen/Core>

#include <cstdint>

#include "server/render/render_types.h"
#include "server/sim/map/map.h"

namespace sim4cv::render {

// One object in its own frame: origin at the centre of its footprint on the
// ground, x along the footprint's half_x, z up (the map's pose turns it about
// z and moves it). `variant` picks colours, so neighbouring houses differ;
// the same arguments always give the same mesh. At most 110 triangles.
Mesh MakeObjectMesh(map::ObjectKind kind, map::Surroundings surroundings, uint32_t variant);

// Where a lantern's light comes from, in its model frame: just under its head.
Eigen::Vector3f LanternLightOffset();

}  // namespace sim4cv::render
