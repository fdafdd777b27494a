// A closed polyline parameterised by arc length: the lane the car follows.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace sim4cv::sim {

class ClosedPath {
 public:
  // At least 3 distinct points, in driving order; the last joins the first.
  explicit ClosedPath(std::vector<Eigen::Vector2d> points);

  // The loop shifted sideways by `offset` metres (positive: to the right of
  // the driving direction), e.g. the right lane's centre from the road's.
  static ClosedPath Offset(const std::vector<Eigen::Vector2d>& centre_line, double offset);

  struct Projection {
    std::size_t segment = 0;  // segment i runs from point i to point i+1 (mod n)
    double arc_length = 0.0;  // from point 0 along the loop
    Eigen::Vector2d point = Eigen::Vector2d::Zero();
  };

  // Nearest point on the loop to `p`. Searches every segment: loops are short
  // and this keeps the answer exact.
  Projection Project(const Eigen::Vector2d& p) const;

  // The point at arc length `s` (any real value; wraps around the loop).
  Eigen::Vector2d PointAt(double s) const;
  // Unit tangent at arc length `s`.
  Eigen::Vector2d TangentAt(double s) const;

  double length() const { return cumulative_.back(); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }

 private:
  std::size_t SegmentAt(double wrapped_s) const;

  std::vector<Eigen::Vector2d> points_;
  std::vector<double> cumulative_;  // arc length at each point; back() = total length
};

}  // namespace sim4cv::sim
