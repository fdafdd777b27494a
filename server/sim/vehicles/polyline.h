// A 2D polyline parameterised by arc length, open or closed: the path the
// car's driver follows, and the scene's closed lane loop.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace sim4cv::vehicles {

// A closed loop's points shifted sideways by `offset` metres (positive: to
// the right of the driving direction), e.g. the right lane's centre from the
// road's; corners move along their bisector, so sides stay parallel.
std::vector<Eigen::Vector2d> OffsetLoop(const std::vector<Eigen::Vector2d>& centre_line, double offset);

class Polyline {
 public:
  // At least 2 points (3 if closed), consecutive points distinct. A closed
  // polyline joins its last point to its first: do not repeat the first point.
  Polyline(std::vector<Eigen::Vector2d> points, bool closed);

  struct Projection {
    double arc_length = 0.0;  // from the first point
    Eigen::Vector2d point = Eigen::Vector2d::Zero();
    double distance = 0.0;  // from the projected point to the path
  };
  // Nearest point on the path (every segment is searched).
  Projection Project(const Eigen::Vector2d& p) const;
  // Nearest point among the segments within `window` metres of path before
  // and after arc length `arc_length`: for tracking progress along a long
  // path cheaply, and without jumping to another part of it that passes close.
  Projection ProjectNear(const Eigen::Vector2d& p, double arc_length, double window) const;

  // The point at arc length `s`. Closed: wraps around. Open: continues
  // straight beyond either end, so a lookahead past the end stays defined.
  Eigen::Vector2d PointAt(double s) const;
  // Unit tangent (driving direction) at arc length `s`.
  Eigen::Vector2d TangentAt(double s) const;

  double length() const { return cumulative_.back(); }
  bool closed() const { return closed_; }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  std::size_t SegmentCount() const { return closed_ ? points_.size() : points_.size() - 1; }
  Projection OntoSegment(std::size_t i, const Eigen::Vector2d& p) const;
  std::size_t SegmentAt(double s) const;  // the segment containing arc length s (clamped to the ends)
  double Wrap(double s) const;            // closed: s into [0, length)
  const Eigen::Vector2d& SegmentEnd(std::size_t i) const { return points_[(i + 1) % points_.size()]; }

  std::vector<Eigen::Vector2d> points_;
  bool closed_;
  std::vector<double> cumulative_;  // arc length at the start of each segment; back() = total length
};

}  // namespace sim4cv::vehicles
