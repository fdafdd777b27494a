// The UAV's camera gimbal (Sim4CV: "a camera set at a 60 degree angle and
// located below the frame", held by a gimbal). A stabilised two-axis mount:
// the camera keeps its pitch below the horizon and stays level whatever the
// body's roll and pitch, and turns only with the body's yaw.
#pragma once

#include <Eigen/Core>

#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

struct GimbalParams {
  double pitch_down_deg = 60.0;                  // below the horizon; 90 looks straight down
  Eigen::Vector3d mount_offset{0.0, 0.0, -0.3};  // m, body frame: the gimbal hangs below the frame
};

// The camera pose for a body pose: position = body position + body rotation
// * mount_offset (the mount is fixed to the frame); orientation =
// Rz(body yaw) * Ry(pitch_down), in the camera frame x = viewing direction,
// y = image left, z = image up. (An OpenGL camera looks along -z with y up:
// LookAt(position, position + R x, R z).)
Pose GimbalCameraPose(const Pose& body, const GimbalParams& gimbal = {});

}  // namespace sim4cv::vehicles
