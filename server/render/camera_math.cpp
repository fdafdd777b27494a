#include "server/render/camera_math.h"

#include <cmath>
#include <numbers>

#include "server/common/check.h"

namespace sim4cv::render {

Eigen::Matrix4f LookAt(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up) {
  const Eigen::Vector3f backward = (eye - target).normalized();  // the camera looks along its -z
  const Eigen::Vector3f right_unnormalised = up.cross(backward);
  SIM4CV_THROW_UNLESS(right_unnormalised.norm() > 1e-6f * up.norm() && (eye - target).norm() > 0.0f,
                      "LookAt: eye == target or up parallel to the viewing direction");
  const Eigen::Vector3f right = right_unnormalised.normalized();
  Eigen::Matrix4f world_from_camera = Eigen::Matrix4f::Identity();
  world_from_camera.block<3, 1>(0, 0) = right;
  world_from_camera.block<3, 1>(0, 1) = backward.cross(right);
  world_from_camera.block<3, 1>(0, 2) = backward;
  world_from_camera.block<3, 1>(0, 3) = eye;
  return world_from_camera;
}

Eigen::Matrix4f Perspective(float fov_y_deg, float aspect, float near_m, float far_m) {
  SIM4CV_THROW_UNLESS(fov_y_deg > 0.0f && fov_y_deg < 180.0f, "fov_y_deg " << fov_y_deg << " must be in (0, 180)");
  SIM4CV_THROW_UNLESS(aspect > 0.0f, "aspect " << aspect << " must be > 0");
  SIM4CV_THROW_UNLESS(near_m > 0.0f && far_m > near_m, "need 0 < near (" << near_m << ") < far (" << far_m << ")");
  const float f = 1.0f / std::tan(0.5f * fov_y_deg * std::numbers::pi_v<float> / 180.0f);
  Eigen::Matrix4f projection = Eigen::Matrix4f::Zero();
  projection(0, 0) = f / aspect;
  projection(1, 1) = f;
  projection(2, 2) = (far_m + near_m) / (near_m - far_m);
  projection(2, 3) = 2.0f * far_m * near_m / (near_m - far_m);
  projection(3, 2) = -1.0f;
  return projection;
}

Eigen::Matrix4f PoseMatrix(const Eigen::Vector3f& position, const Eigen::Quaternionf& orientation) {
  Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
  pose.topLeftCorner<3, 3>() = orientation.normalized().toRotationMatrix();
  pose.block<3, 1>(0, 3) = position;
  return pose;
}

Eigen::Matrix4f RigidInverse(const Eigen::Matrix4f& rigid) {
  Eigen::Matrix4f inverse = Eigen::Matrix4f::Identity();
  const Eigen::Matrix3f rotation_transposed = rigid.topLeftCorner<3, 3>().transpose();
  inverse.topLeftCorner<3, 3>() = rotation_transposed;
  inverse.block<3, 1>(0, 3) = -rotation_transposed * rigid.block<3, 1>(0, 3);
  return inverse;
}

std::array<Eigen::Vector4f, 6> FrustumPlanes(const Eigen::Matrix4f& clip_from_world) {
  std::array<Eigen::Vector4f, 6> planes;
  const Eigen::Vector4f w = clip_from_world.row(3).transpose();
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector4f row = clip_from_world.row(axis).transpose();
    planes[2 * axis] = w + row;
    planes[2 * axis + 1] = w - row;
  }
  for (Eigen::Vector4f& plane : planes) plane /= plane.head<3>().norm();
  return planes;
}

}  // namespace sim4cv::render
