// What a quadcopter is, apart from its Bullet body (quadcopter.h), so the
// Scene and the renderer know UAVs without depending on the physics engine.
#pragma once

#include <Eigen/Core>

namespace sim4cv::vehicles {

struct QuadcopterParams {
  double mass = 1.5;                             // kg
  Eigen::Vector3d half_extents{0.3, 0.3, 0.05};  // m (0.6 m span, 0.1 m tall box)
  double linear_damping = 0.1;                   // Bullet's: velocity *= (1 - d)^dt, i.e. drag ~0.105/s
  double angular_damping = 0.2;                  // Bullet's, on the angular velocity
  double max_thrust = 2.5 * 1.5 * 9.81;          // N (thrust-to-weight 2.5)
  Eigen::Vector3d max_torque{2.0, 2.0, 0.5};     // N m about body x, y, z
};

}  // namespace sim4cv::vehicles
