#include "server/render/projection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace sim4cv::render {
namespace {

// OpenGL's camera looks along -z with y up; OpenCV's along +z with y down.
// Turning half a revolution about x maps one onto the other.
Eigen::Matrix3d OpenCvFromOpenGl() { return Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal(); }

Eigen::Matrix3d WorldFromOpenCvCamera(const CameraView& view) {
  return view.world_from_camera.topLeftCorner<3, 3>().cast<double>() * OpenCvFromOpenGl();
}

}  // namespace

CameraIntrinsics IntrinsicsOf(const CameraView& view) {
  // The same focal length the renderer's Perspective() implies, in pixels:
  // clip-space y spans `height` pixels over [-1, 1].
  const double half_fov = 0.5 * static_cast<double>(view.fov_y_deg) * std::numbers::pi / 180.0;
  CameraIntrinsics intrinsics;
  intrinsics.fy = 0.5 * view.height / std::tan(half_fov);
  intrinsics.fx = intrinsics.fy;
  intrinsics.cx = 0.5 * view.width;
  intrinsics.cy = 0.5 * view.height;
  intrinsics.width = view.width;
  intrinsics.height = view.height;
  intrinsics.lens = view.effects;
  return intrinsics;
}

Pose OpenCvPoseOf(const CameraView& view) {
  Pose pose;
  pose.position = view.world_from_camera.block<3, 1>(0, 3).cast<double>();
  pose.orientation = Eigen::Quaterniond(WorldFromOpenCvCamera(view)).normalized();
  return pose;
}

BoxProjector::BoxProjector(const CameraView& view)
    : intrinsics_(IntrinsicsOf(view)), camera_from_world_(WorldFromOpenCvCamera(view).transpose()),
      camera_origin_(view.world_from_camera.block<3, 1>(0, 3).cast<double>()), near_m_(view.near_m),
      far_m_(view.far_m) {}

Eigen::Vector2d BoxProjector::ToPixel(const Eigen::Vector3d& camera_point) const {
  double x = camera_point.x() / camera_point.z(), y = camera_point.y() / camera_point.z();
  if (effects::Distorts(intrinsics_.lens)) effects::Distort(intrinsics_.lens, x, y, x, y);
  return {intrinsics_.fx * x + intrinsics_.cx, intrinsics_.fy * y + intrinsics_.cy};
}

ImageRect BoxProjector::Project(const Eigen::Vector3d& centre, const Eigen::Quaterniond& orientation,
                                const Eigen::Vector3d& half_extents) const {
  // Corner i has sign (-1)^(bit k of i) along box axis k.
  const Eigen::Matrix3d axes = camera_from_world_ * orientation.toRotationMatrix();
  const Eigen::Vector3d middle = camera_from_world_ * (centre - camera_origin_);
  std::array<Eigen::Vector3d, 8> corners;
  double nearest = std::numeric_limits<double>::infinity(), farthest = -nearest;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d sign((i & 1) ? -1.0 : 1.0, (i & 2) ? -1.0 : 1.0, (i & 4) ? -1.0 : 1.0);
    corners[i] = middle + axes * sign.cwiseProduct(half_extents);
    nearest = std::min(nearest, corners[i].z());
    farthest = std::max(farthest, corners[i].z());
  }
  if (farthest < near_m_ || nearest > far_m_) return {};

  // The projection of a convex solid is bounded by the projections of its
  // vertices; clipped by the near plane, those are the corners in front of it
  // and the points where edges cross it.
  Eigen::Vector2d low = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d high = -low;
  const auto include = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector2d pixel = ToPixel(p);
    low = low.cwiseMin(pixel);
    high = high.cwiseMax(pixel);
  };
  // A lens bends straight edges: their extremes may lie between the corners.
  const int steps = effects::Distorts(intrinsics_.lens) ? 256 : 0;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d& a = corners[i];
    if (a.z() >= near_m_) include(a);
    for (int bit : {1, 2, 4}) {
      if (i & bit) continue;  // each edge once: from the corner without the bit
      const Eigen::Vector3d& b = corners[i | bit];
      if ((a.z() < near_m_) != (b.z() < near_m_)) include(a + (b - a) * ((near_m_ - a.z()) / (b.z() - a.z())));
      for (int k = 1; k < steps; ++k) {
        const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / steps);
        if (p.z() >= near_m_) include(p);
      }
    }
  }
  const double x0 = std::max(low.x(), 0.0), y0 = std::max(low.y(), 0.0);
  const double x1 = std::min(high.x(), static_cast<double>(intrinsics_.width));
  const double y1 = std::min(high.y(), static_cast<double>(intrinsics_.height));
  if (!(x1 > x0 && y1 > y0)) return {};
  return {static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(x1 - x0), static_cast<float>(y1 - y0)};
}

}  // namespace sim4cv::render
