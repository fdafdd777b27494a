// Rigid poses and pinhole projections in the conventions the renderer uses:
// the world is z-up, a camera frame follows OpenGL (x right, y up, looking
// along -z), and projections map to OpenGL clip space (z in [-w, w]).
#pragma once

#include <array>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace sim4cv::render {

// world_from_camera of a camera at `eye` looking at `target`, with `up`
// (which must not be parallel to the viewing direction) pointing up in the image.
Eigen::Matrix4f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up);

// OpenGL perspective projection (as gluPerspective) with a vertical field of view.
Eigen::Matrix4f Perspective(float fov_y_deg, float aspect, float near_m, float far_m);

// The homogeneous transform of a pose: rotation `orientation`, then translation `position`.
Eigen::Matrix4f PoseMatrix(const Eigen::Vector3f& position, const Eigen::Quaternionf& orientation);

// Inverse of a rigid transform (rotation + translation), cheaper and more exact
// than a general 4x4 inverse.
Eigen::Matrix4f RigidInverse(const Eigen::Matrix4f& rigid);

// The six planes (a, b, c, d) of the frustum of `clip_from_world`, normals pointing
// inside and of unit length: a world point p is inside where a p.x + b p.y + c p.z + d >= 0
// for all six (Gribb & Hartmann).
std::array<Eigen::Vector4f, 6> FrustumPlanes(const Eigen::Matrix4f& clip_from_world);

}  // namespace sim4cv::render
