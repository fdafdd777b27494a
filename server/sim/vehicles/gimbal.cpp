#include "server/sim/vehicles/gimbal.h"

#include <numbers>

namespace sim4cv::vehicles {

Pose GimbalCameraPose(const Pose& body, const GimbalParams& gimbal) {
  // A positive rotation about y tips the x axis below the horizon.
  const double pitch = gimbal.pitch_down_deg * std::numbers::pi / 180.0;
  return {body.position + body.orientation * gimbal.mount_offset,
          Eigen::Quaterniond(Eigen::AngleAxisd(Yaw(body.orientation), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()))};
}

}  // namespace sim4cv::vehicles
