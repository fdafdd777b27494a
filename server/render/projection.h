// The camera model clients receive with every frame (docs/protocol.md §9):
// pinhole intrinsics, the camera's pose in OpenCV's axis convention, and the
// projection of an oriented 3D box into the image. The renderer works in
// OpenGL's convention (camera_math.h); this is the one place that converts,
// so what clients are told and what was drawn cannot drift apart.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "server/render/render_types.h"

namespace sim4cv::render {

// Pixel coordinates are continuous with the origin at the image's top-left
// corner: pixel column c spans [c, c + 1), so its centre is at c + 0.5.
struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0;  // focal lengths, pixels
  double cx = 0.0, cy = 0.0;  // principal point, pixels
  uint32_t width = 0, height = 0;
  // The lens (protocol/effects.h), applied to (x/z, y/z) before fx, cx.
  effects::CameraEffects lens;
};

// A rigid pose: maps the frame's coordinates into world coordinates.
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

// An axis-aligned rectangle in the continuous pixel coordinates above.
struct ImageRect {
  float x = 0.0f, y = 0.0f, width = 0.0f, height = 0.0f;

  bool empty() const { return !(width > 0.0f && height > 0.0f); }
};

// Square pixels and the principal point at the image centre:
// fx = fy = (height / 2) / tan(fov_y / 2), cx = width / 2, cy = height / 2.
CameraIntrinsics IntrinsicsOf(const CameraView& view);

// The camera's pose with OpenCV's axes: x right (along image columns), y down
// (along rows), z forward (the optical axis), so that a point p in these
// coordinates lands on pixel (fx * p.x / p.z + cx, fy * p.y / p.z + cy).
Pose OpenCvPoseOf(const CameraView& view);

// Projects oriented boxes into one camera's image; built once per frame.
class BoxProjector {
 public:
  explicit BoxProjector(const CameraView& view);

  // The tight rectangle around the image of the part of the box (centre and
  // orientation in the world, half extents along its own axes) that lies in
  // front of the near plane, clipped to the image: the object's extent as if
  // nothing occluded it. Corners behind the near plane are replaced by the
  // points where the box's edges cross it, so a box around the camera still
  // projects correctly. Empty if no part of the box is in view or all of it
  // lies beyond the far plane. With a lens, edges bow: each is followed in
  // small steps, so the rectangle is within a hundredth of a pixel of the
  // curve's extent.
  ImageRect Project(const Eigen::Vector3d& centre, const Eigen::Quaterniond& orientation,
                    const Eigen::Vector3d& half_extents) const;

  // The pixel a point in OpenCV camera coordinates (z > 0) lands on,
  // through the lens if the camera has one.
  Eigen::Vector2d ToPixel(const Eigen::Vector3d& camera_point) const;

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }

 private:
  CameraIntrinsics intrinsics_;
  Eigen::Matrix3d camera_from_world_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d camera_origin_ = Eigen::Vector3d::Zero();  // world
  double near_m_ = 0.1, far_m_ = 1000.0;
};

}  // namespace sim4cv::render
