// The Bullet plumbing the vehicles share: Eigen <-> Bullet conversions and a
// rigid body that lives in a caller-owned world for as long as this object.
#pragma once

#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

inline btVector3 ToBullet(const Eigen::Vector3d& v) {
  return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z()));
}
inline btQuaternion ToBullet(const Eigen::Quaterniond& q) {
  return btQuaternion(btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w()));
}
inline Eigen::Vector3d FromBullet(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
inline Eigen::Quaterniond FromBullet(const btQuaternion& q) { return {q.w(), q.x(), q.y(), q.z()}; }
inline btTransform ToBullet(const Pose& pose) {
  return btTransform(ToBullet(pose.orientation), ToBullet(pose.position));
}

// A rigid body added to `world` on construction and removed on destruction.
// `shape` must outlive it. Mass 0 makes a static body; pass
// btCollisionObject::CF_KINEMATIC_OBJECT in `collision_flags` for a kinematic
// one (the flag has to be set before the body joins the world, or the
// broadphase files it as static).
class BodyInWorld {
 public:
  BodyInWorld(btDiscreteDynamicsWorld& world, btCollisionShape& shape, double mass, const btTransform& pose,
              int collision_flags = 0);
  ~BodyInWorld();
  BodyInWorld(const BodyInWorld&) = delete;
  BodyInWorld& operator=(const BodyInWorld&) = delete;

  btRigidBody& body() { return body_; }
  const btRigidBody& body() const { return body_; }

  // Pose and velocity of the point `point_in_body` (body frame, relative to
  // the centre of mass) rigidly attached to the body.
  VehicleState StateAt(const Eigen::Vector3d& point_in_body) const;

  // Places the body at `pose` (the centre of mass) at rest: for spawning and
  // resets only, never for control.
  void Teleport(const btTransform& pose);

 private:
  static btRigidBody::btRigidBodyConstructionInfo Info(btCollisionShape& shape, double mass, btMotionState* motion);

  btDiscreteDynamicsWorld& world_;
  btDefaultMotionState motion_;
  btRigidBody body_;
};

}  // namespace sim4cv::vehicles
