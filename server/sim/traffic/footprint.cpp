#include "server/sim/traffic/footprint.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sim4cv::traffic {
namespace {

Eigen::Vector2d Axis(double heading) { return {std::cos(heading), std::sin(heading)}; }

// Half the box's extent along the unit direction `d`.
double Reach(const Box2& box, const Eigen::Vector2d& d) {
  const Eigen::Vector2d x = Axis(box.heading);
  const Eigen::Vector2d y(-x.y(), x.x());
  return box.half_x * std::abs(x.dot(d)) + box.half_y * std::abs(y.dot(d));
}

}  // namespace

Box2 FootprintOf(const map::MapObject& object) {
  const map::ObjectShape& shape = map::ShapeOf(object.kind);
  return {object.position, object.rotation_deg * std::numbers::pi / 180.0, shape.half_x, shape.half_y};
}

std::array<Eigen::Vector2d, 4> Corners(const Box2& box) {
  const Eigen::Vector2d x = Axis(box.heading) * box.half_x;
  const Eigen::Vector2d y = Eigen::Vector2d(-std::sin(box.heading), std::cos(box.heading)) * box.half_y;
  return {box.centre - x - y, box.centre + x - y, box.centre + x + y, box.centre - x + y};
}

Box2 Grown(const Box2& box, double margin) {
  return {box.centre, box.heading, box.half_x + margin, box.half_y + margin};
}

bool Overlap(const Box2& a, const Box2& b) {
  const Eigen::Vector2d between = b.centre - a.centre;
  for (double heading : {a.heading, a.heading + std::numbers::pi / 2, b.heading, b.heading + std::numbers::pi / 2}) {
    const Eigen::Vector2d d = Axis(heading);
    if (std::abs(between.dot(d)) > Reach(a, d) + Reach(b, d)) return false;
  }
  return true;
}

double DistanceTo(const Box2& box, const Eigen::Vector2d& p) {
  const Eigen::Vector2d x = Axis(box.heading);
  const Eigen::Vector2d local = p - box.centre;
  const double dx = std::max(0.0, std::abs(local.dot(x)) - box.half_x);
  const double dy = std::max(0.0, std::abs(x.x() * local.y() - x.y() * local.x()) - box.half_y);
  return std::hypot(dx, dy);
}

}  // namespace sim4cv::traffic
