#include "server/sim/vehicles/polyline.h"

#include <algorithm>
#include <cmath>

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

Polyline::Projection Polyline::OntoSegment(std::size_t i, const Eigen::Vector2d& p) const {
  const Eigen::Vector2d& a = points_[i];
  const Eigen::Vector2d ab = SegmentEnd(i) - a;
  const double t = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  const Eigen::Vector2d q = a + t * ab;
  return {cumulative_[i] + t * (cumulative_[i + 1] - cumulative_[i]), q, (p - q).norm()};
}

Polyline::Projection Polyline::Project(const Eigen::Vector2d& p) const {
  Projection best = OntoSegment(0, p);
  for (std::size_t i = 1; i < SegmentCount(); ++i) {
    const Projection candidate = OntoSegment(i, p);
    if (candidate.distance < best.distance) best = candidate;
  }
  return best;
}

Polyline::Projection Polyline::ProjectNear(const Eigen::Vector2d& p, double arc_length, double window) const {
  const std::size_t n = SegmentCount();
  const std::size_t start = SegmentAt(Wrap(arc_length));
  Projection best = OntoSegment(start, p);
  auto consider = [&](std::size_t i) {
    const Projection candidate = OntoSegment(i, p);
    if (candidate.distance < best.distance) best = candidate;
  };
  // Walk outwards from the hint's segment, forwards and backwards, until
  // `window` metres of path are covered each way (or the path ends).
  double ahead = cumulative_[start + 1] - Wrap(arc_length);
  for (std::size_t k = 1; k < n && ahead < window; ++k) {
    if (!closed_ && start + k >= n) break;
    const std::size_t i = (start + k) % n;
    consider(i);
    ahead += cumulative_[i + 1] - cumulative_[i];
  }
  double behind = Wrap(arc_length) - cumulative_[start];
  for (std::size_t k = 1; k < n && behind < window; ++k) {
    if (!closed_ && k > start) break;
    const std::size_t i = (start + n - k) % n;
    consider(i);
    behind += cumulative_[i + 1] - cumulative_[i];
  }
  return best;
}

double Polyline::Wrap(double s) const { return closed_ ? s - std::floor(s / length()) * length() : s; }

std::size_t Polyline::SegmentAt(double s) const {
  // Before an open path's start, the first segment; past its end, the last.
  const auto it = std::upper_bound(cumulative_.begin(), cumulative_.end(), s);
  const std::ptrdiff_t i = std::max<std::ptrdiff_t>(it - cumulative_.begin() - 1, 0);
  return std::min(static_cast<std::size_t>(i), SegmentCount() - 1);
}

Eigen::Vector2d Polyline::PointAt(double s) const {
  s = Wrap(s);
  // Beyond an open end, the end segment extrapolated.
  const std::size_t i = SegmentAt(s);
  const Eigen::Vector2d& a = points_[i];
  const double t = (s - cumulative_[i]) / (cumulative_[i + 1] - cumulative_[i]);
  return a + t * (SegmentEnd(i) - a);
}

Eigen::Vector2d Polyline::TangentAt(double s) const {
  const std::size_t i = SegmentAt(Wrap(s));
  return (SegmentEnd(i) - points_[i]).normalized();
}

std::vector<Eigen::Vector2d> OffsetLoop(const std::vector<Eigen::Vector2d>& centre_line, double offset) {
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
  return shifted;
}

}  // namespace sim4cv::vehicles
