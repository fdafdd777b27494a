#include "server/sim/map/lane_curve.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "server/common/check.h"

namespace sim4cv::map {

double WrapAngle(double radians) {
  const double two_pi = 2 * std::numbers::pi;
  double wrapped = std::fmod(radians + std::numbers::pi, two_pi);
  if (wrapped <= 0) wrapped += two_pi;
  return wrapped - std::numbers::pi;
}

Eigen::Vector2d Piece::PointAt(double s) const {
  const double h = heading;
  if (curvature == 0.0) return start + s * Eigen::Vector2d(std::cos(h), std::sin(h));
  const double h_end = h + curvature * s;
  return start + Eigen::Vector2d(std::sin(h_end) - std::sin(h), std::cos(h) - std::cos(h_end)) / curvature;
}

double Piece::Project(const Eigen::Vector2d& p) const {
  const Eigen::Vector2d forward(std::cos(heading), std::sin(heading));
  if (curvature == 0.0) return std::clamp((p - start).dot(forward), 0.0, length);
  const Eigen::Vector2d left(-forward.y(), forward.x());
  const Eigen::Vector2d centre = start + left / curvature;
  const Eigen::Vector2d from_centre = p - centre;
  if (from_centre.squaredNorm() < 1e-24) return 0.0;  // every point of the arc is equally near
  const Eigen::Vector2d start_from_centre = start - centre;
  const double swept =
      std::atan2(from_centre.y(), from_centre.x()) - std::atan2(start_from_centre.y(), start_from_centre.x());
  // Angle travelled from the start to p's direction, in [0, 2 pi).
  double travelled = std::fmod((curvature > 0 ? swept : -swept), 2 * std::numbers::pi);
  if (travelled < 0) travelled += 2 * std::numbers::pi;
  const double s = travelled / std::abs(curvature);
  if (s <= length) return s;
  // Beyond the arc's ends: the nearer end wins.
  return (p - PointAt(0)).squaredNorm() <= (p - PointAt(length)).squaredNorm() ? 0.0 : length;
}

void LaneCurve::Add(double length, double curvature) {
  SIM4CV_DEMAND(length > 0);
  const Piece piece{end_, end_heading_, length, curvature};
  pieces_.push_back(piece);
  starts_.push_back(total_length_);
  total_length_ += length;
  end_ = piece.PointAt(length);
  end_heading_ = piece.HeadingAt(length);
}

LaneCurve& LaneCurve::Straight(double length) {
  Add(length, 0.0);
  return *this;
}

LaneCurve& LaneCurve::Arc(double radius, double angle) {
  SIM4CV_DEMAND(radius > 0);
  Add(radius * std::abs(angle), angle > 0 ? 1.0 / radius : -1.0 / radius);
  return *this;
}

const Piece& LaneCurve::PieceAt(double s, double* local_s) const {
  SIM4CV_DEMAND(!pieces_.empty());
  s = std::clamp(s, 0.0, total_length_);
  const auto it = std::upper_bound(starts_.begin(), starts_.end(), s);
  const std::size_t i = static_cast<std::size_t>(it - starts_.begin()) - 1;
  *local_s = std::min(s - starts_[i], pieces_[i].length);
  return pieces_[i];
}

Eigen::Vector2d LaneCurve::PointAt(double s) const {
  double local = 0;
  const Piece& piece = PieceAt(s, &local);
  return piece.PointAt(local);
}

double LaneCurve::HeadingAt(double s) const {
  double local = 0;
  const Piece& piece = PieceAt(s, &local);
  return WrapAngle(piece.HeadingAt(local));
}

double LaneCurve::CurvatureAt(double s) const {
  double local = 0;
  return PieceAt(s, &local).curvature;
}

LaneCurve::Nearest LaneCurve::Project(const Eigen::Vector2d& p) const {
  Nearest best{0.0, std::numeric_limits<double>::infinity()};
  for (std::size_t i = 0; i < pieces_.size(); ++i) {
    const double local = pieces_[i].Project(p);
    const double distance = (p - pieces_[i].PointAt(local)).norm();
    if (distance < best.distance) best = {starts_[i] + local, distance};
  }
  return best;
}

}  // namespace sim4cv::map
