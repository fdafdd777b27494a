// A lane's centre line as a chain of pieces of constant curvature: straight
// lines and circular arcs. Exact, so the driving case study's waypoints and
// lateral offsets carry no polyline error.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace sim4cv::map {

// Wraps an angle to (-pi, pi].
double WrapAngle(double radians);

// A straight (curvature 0) or a circular arc (curvature 1/radius, positive
// turning left, i.e. counter-clockwise seen from above).
struct Piece {
  Eigen::Vector2d start{0, 0};
  double heading = 0.0;  // radians at the start, counter-clockwise from east
  double length = 0.0;   // metres
  double curvature = 0.0;

  Eigen::Vector2d PointAt(double s) const;
  double HeadingAt(double s) const { return heading + curvature * s; }
  // Arc length in [0, length] of this piece's point nearest to `p`.
  double Project(const Eigen::Vector2d& p) const;
};

class LaneCurve {
 public:
  LaneCurve() = default;
  // An empty curve that starts at `start` heading `heading`; pieces are added
  // end to end, so a curve is continuous in position and heading by construction.
  LaneCurve(const Eigen::Vector2d& start, double heading) : end_(start), end_heading_(heading) {}

  LaneCurve& Straight(double length);
  // An arc of `radius` turning through `angle` radians (positive: left).
  LaneCurve& Arc(double radius, double angle);

  double length() const { return total_length_; }
  const std::vector<Piece>& pieces() const { return pieces_; }

  // `s` is clamped to [0, length].
  Eigen::Vector2d PointAt(double s) const;
  double HeadingAt(double s) const;  // wrapped to (-pi, pi]
  double CurvatureAt(double s) const;

  struct Nearest {
    double s = 0.0;         // arc length of the nearest point
    double distance = 0.0;  // from the query point to it
  };
  Nearest Project(const Eigen::Vector2d& p) const;

 private:
  const Piece& PieceAt(double s, double* local_s) const;
  void Add(double length, double curvature);

  std::vector<Piece> pieces_;
  std::vector<double> starts_;  // arc length at the start of each piece
  double total_length_ = 0.0;
  Eigen::Vector2d end_{0, 0};
  double end_heading_ = 0.0;
};

}  // namespace sim4cv::map
