#include "server/sim/vehicles/polyline.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "server/common/check.h"

namespace sim4cv::vehicles {

Polyline::Polyline(std::vector<Eigen::Vector2d> points, bool closed) : points_(std::move(points)), closed_(closed) {
  const std::size_t minimum = closed_ ? 3 : 2;
  SIM4CV_THROW_UNLESS(points_.size() >= minimum, (closed_ ? "a closed" : "an open")
                                                     << " path needs at least " << minimum << " points, got "
                                                     << points_.size());
  cumulative_.push_back(0.0);
  for (std::size_t i = 0; i < SegmentCount(); ++i) {
    const double segment = (SegmentEnd(i) - points_[i]).norm();
    SIM4CV_THROW_UNLESS(segment > 1e-6, "path points " << i << " and " << (i + 1) % points_.size() << " coincide");
    cumulative_.push_back(cumulative_.back() + segment);
  }
}

Polyline::Projection Polyline::Project(const Eigen::Vector2d& p) const {
  Projection best;
  best.distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < SegmentCount(); ++i) {
    const Eigen::Vector2d& a = points_[i];
    const Eigen::Vector2d ab = SegmentEnd(i) - a;
    const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
    const Eigen::Vector2d q = a + t * ab;
    const double distance = (p - q).norm();
    if (distance < best.distance) best = {cumulative_[i] + t * (cumulative_[i + 1] - cumulative_[i]), q, distance};
  }
  return best;
}

Eigen::Vector2d Polyline::PointAt(double s) const {
  if (closed_) s -= std::floor(s / length()) * length();
  // Segment containing s; beyond an open end, the end segment extrapolated.
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  const std::size_t i = std::min<std::size_t>(
      static_cast<std::size_t>(std::max<std::ptrdiff_t>(it - cumulative_.begin() - 1, 0)), SegmentCount() - 1);
  const Eigen::Vector2d& a = points_[i];
  const double t = (s - cumulative_[i]) / (cumulative_[i + 1] - cumulative_[i]);
  return a + t * (SegmentEnd(i) - a);
}

}  // namespace sim4cv::vehicles
