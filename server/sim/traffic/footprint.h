// Oriented rectangles on the ground, for keeping traffic clear of the map's
// objects and of itself while the plan is laid out.
#pragma once

#include <Eigen/Core>
#include <array>

#include "server/sim/map/map.h"

namespace sim4cv::traffic {

struct Box2 {
  Eigen::Vector2d centre{0, 0};
  double heading = 0.0;  // of the box's own x axis, radians
  double half_x = 0.0, half_y = 0.0;
};

// The footprint ShapeOf gives the object's kind, placed and turned as the map says.
Box2 FootprintOf(const map::MapObject& object);
std::array<Eigen::Vector2d, 4> Corners(const Box2& box);
// The same box, `margin` larger on every side.
Box2 Grown(const Box2& box, double margin);
// Whether two boxes overlap (separating axes; touching counts).
bool Overlap(const Box2& a, const Box2& b);
// Distance from `p` to the box, 0 inside it.
double DistanceTo(const Box2& box, const Eigen::Vector2d& p);

}  // namespace sim4cv::traffic
