// A quadcopter as one Bullet rigid body (a box) that is moved only by a
// thrust force along its body z axis and body torques: gravity, mass,
// inertia and damping do the rest. A QuadcopterController computes both
// every physics substep. Parameters: docs/vehicles.md.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>

#include "server/sim/vehicles/bullet_body.h"
#include "server/sim/vehicles/quadcopter_controller.h"
#include "server/sim/vehicles/quadcopter_params.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

class Quadcopter {
 public:
  // Spawns the UAV level at `position`, heading `yaw`, at rest, holding that
  // position's altitude with zero velocity command.
  Quadcopter(btDiscreteDynamicsWorld& world, const QuadcopterParams& params, const Eigen::Vector3d& position,
             double yaw, const QuadcopterGains& gains = {});
  Quadcopter(const Quadcopter&) = delete;
  Quadcopter& operator=(const Quadcopter&) = delete;

  void SetCommand(const QuadcopterCommand& command) { command_ = command; }
  const QuadcopterCommand& command() const { return command_; }

  // Runs the controller on the current state and applies its thrust and
  // torque for the next physics step. Call once before every
  // world.stepSimulation(dt, 0).
  void Update(double dt);

  VehicleState State() const { return body_.StateAt(Eigen::Vector3d::Zero()); }
  const QuadcopterParams& params() const { return params_; }
  btRigidBody& body() { return body_.body(); }

  // Places the UAV as the constructor does (spawning and resets only).
  void Reset(const Eigen::Vector3d& position, double yaw);

 private:
  static btTransform SpawnPose(const Eigen::Vector3d& position, double yaw);

  QuadcopterParams params_;
  btBoxShape box_;
  BodyInWorld body_;
  QuadcopterController controller_;
  QuadcopterCommand command_;
  QuadcopterActuation actuation_;
};

}  // namespace sim4cv::vehicles
