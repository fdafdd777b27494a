#include "server/sim/vehicles/quadcopter.h"

#include <cmath>

#include "server/common/check.h"

namespace sim4cv::vehicles {
namespace {

// Checks the parameters before anything is built from them.
btVector3 HalfExtents(const QuadcopterParams& params) {
  SIM4CV_THROW_UNLESS(params.mass > 0, "quadcopter mass " << params.mass << " must be > 0");
  SIM4CV_THROW_UNLESS(params.linear_damping >= 0 && params.linear_damping < 1,
                      "quadcopter linear damping " << params.linear_damping << " must be in [0, 1)");
  SIM4CV_THROW_UNLESS(params.max_thrust > params.mass * 9.81,
                      "quadcopter max thrust " << params.max_thrust << " N cannot lift " << params.mass << " kg");
  return ToBullet(params.half_extents);
}

QuadcopterModel Model(const QuadcopterParams& params, const btRigidBody& body) {
  const btVector3 inverse_inertia = body.getInvInertiaDiagLocal();
  QuadcopterModel model;
  model.mass = params.mass;
  model.inertia = {1.0 / inverse_inertia.x(), 1.0 / inverse_inertia.y(), 1.0 / inverse_inertia.z()};
  // Bullet's damping scales the velocity by (1 - d)^dt per step: a drag
  // acceleration of -ln(1 - d) per m/s.
  model.drag = -std::log(1.0 - params.linear_damping);
  model.max_thrust = params.max_thrust;
  model.max_torque = params.max_torque;
  return model;
}

}  // namespace

btTransform Quadcopter::SpawnPose(const Eigen::Vector3d& position, double yaw) {
  return btTransform(btQuaternion(btVector3(0, 0, 1), btScalar(yaw)), ToBullet(position));
}

Quadcopter::Quadcopter(btDiscreteDynamicsWorld& world, const QuadcopterParams& params, const Eigen::Vector3d& position,
                       double yaw, const QuadcopterGains& gains)
    : params_(params),
      box_(HalfExtents(params)),
      body_(world, box_, params.mass, SpawnPose(position, yaw)),
      controller_(gains, Model(params, body_.body())) {
  body_.body().setDamping(btScalar(params.linear_damping), btScalar(params.angular_damping));
  Reset(position, yaw);
}

void Quadcopter::Reset(const Eigen::Vector3d& position, double yaw) {
  body_.Teleport(SpawnPose(position, yaw));
  controller_.Reset(State());
  command_ = QuadcopterCommand{};
  actuation_ = QuadcopterActuation{};
}

void Quadcopter::Update(double dt) {
  SIM4CV_DEMAND(dt > 0);
  actuation_ = controller_.Update(command_, State(), dt);
  btRigidBody& body = body_.body();
  const btMatrix3x3& rotation = body.getCenterOfMassTransform().getBasis();
  // Forces are cleared after every stepSimulation, so these act for exactly
  // the next step.
  body.applyCentralForce(rotation * btVector3(0, 0, btScalar(actuation_.thrust)));
  body.applyTorque(rotation * ToBullet(actuation_.torque));
}

}  // namespace sim4cv::vehicles
