#include "server/sim/vehicles/bullet_body.h"

namespace sim4cv::vehicles {

btRigidBody::btRigidBodyConstructionInfo BodyInWorld::Info(btCollisionShape& shape, double mass,
                                                           btMotionState* motion) {
  btVector3 inertia(0, 0, 0);
  if (mass > 0) shape.calculateLocalInertia(btScalar(mass), inertia);
  return btRigidBody::btRigidBodyConstructionInfo(btScalar(mass), motion, &shape, inertia);
}

BodyInWorld::BodyInWorld(btDiscreteDynamicsWorld& world, btCollisionShape& shape, double mass, const btTransform& pose,
                         int collision_flags)
    : world_(world), motion_(pose), body_(Info(shape, mass, &motion_)) {
  body_.setCollisionFlags(body_.getCollisionFlags() | collision_flags);
  // Vehicles are driven every step; a sleeping body would ignore its forces.
  body_.setActivationState(DISABLE_DEACTIVATION);
  world_.addRigidBody(&body_);
}

BodyInWorld::~BodyInWorld() { world_.removeRigidBody(&body_); }

VehicleState BodyInWorld::StateAt(const Eigen::Vector3d& point_in_body) const {
  const btTransform& t = body_.getCenterOfMassTransform();
  const btVector3 offset_world = t.getBasis() * ToBullet(point_in_body);
  VehicleState state;
  state.position = FromBullet(t.getOrigin() + offset_world);
  state.orientation = FromBullet(t.getRotation());
  state.linear_velocity = FromBullet(body_.getVelocityInLocalPoint(offset_world));
  state.angular_velocity = FromBullet(body_.getAngularVelocity());
  return state;
}

void BodyInWorld::Teleport(const btTransform& pose) {
  body_.setCenterOfMassTransform(pose);
  motion_.setWorldTransform(pose);
  body_.setLinearVelocity(btVector3(0, 0, 0));
  body_.setAngularVelocity(btVector3(0, 0, 0));
  body_.clearForces();
}

}  // namespace sim4cv::vehicles
