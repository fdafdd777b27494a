#include "server/sim/closed_path.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "server/common/check.h"

namespace sim4cv::sim {

ClosedPath::ClosedPath(std::vector<Eigen::Vector2d> points) : points_(std::move(points)) {
  SIM4CV_THROW_UNLESS(points_.size() >= 3, "a closed path needs at least 3 points, got " << points_.size());
  cumulative_.reserve(points_.size() + 1);
  cumulative_.push_back(0.0);
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const double segment = (points_[(i + 1) % points_.size()] - points_[i]).norm();
    SIM4CV_THROW_UNLESS(segment > 1e-6, "path points " << i << " and " << (i + 1) % points_.size() << " coincide");
    cumulative_.push_back(cumulative_.back() + segment);
  }
}

ClosedPath ClosedPath::Offset(const std::vector<Eigen::Vector2d>& centre_line, double offset) {
  const std::size_t n = centre_line.size();
  SIM4CV_THROW_UNLESS(n >= 3, "a closed path needs at least 3 points, got " << n);
  std::vector<Eigen::Vector2d> shifted;
  shifted.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    // Average the directions of the two segments meeting here, so corners
    // shift along their bisector.
    const Eigen::Vector2d in = (centre_line[i] - centre_line[(i + n - 1) % n]).normalized();
    const Eigen::Vector2d out = (centre_line[(i + 1) % n] - centre_line[i]).normalized();
    const Eigen::Vector2d direction = (in + out).normalized();
    const Eigen::Vector2d right(direction.y(), -direction.x());
    const double miter = 1.0 / std::max(0.5, right.dot(Eigen::Vector2d(out.y(), -out.x())));
    shifted.push_back(centre_line[i] + right * offset * miter);
  }
  return ClosedPath(std::move(shifted));
}

ClosedPath::Projection ClosedPath::Project(const Eigen::Vector2d& p) const {
  Projection best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Eigen::Vector2d& a = points_[i];
    const Eigen::Vector2d ab = points_[(i + 1) % points_.size()] - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector2d q = a + t * ab;
    const double distance = (p - q).squaredNorm();
    if (distance < best_distance) {
      best_distance = distance;
      best = {i, cumulative_[i] + t * ab.norm(), q};
    }
  }
  return best;
}

std::size_t ClosedPath::SegmentAt(double wrapped_s) const {
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), wrapped_s);
  return std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()) - 1, points_.size() - 1);
}

Eigen::Vector2d ClosedPath::PointAt(double s) const {
  const double wrapped = s - std::floor(s / length()) * length();
  const std::size_t i = SegmentAt(wrapped);
  const Eigen::Vector2d& a = points_[i];
  const Eigen::Vector2d& b = points_[(i + 1) % points_.size()];
  const double t = (wrapped - cumulative_[i]) / (cumulative_[i + 1] - cumulative_[i]);
  return a + t * (b - a);
}

Eigen::Vector2d ClosedPath::TangentAt(double s) const {
  const double wrapped = s - std::floor(s / length()) * length();
  const std::size_t i = SegmentAt(wrapped);
  return (points_[(i + 1) % points_.size()] - points_[i]).normalized();
}

}  // namespace sim4cv::sim
