#include "server/sim/vehicles/car.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "server/common/check.h"

namespace sim4cv::vehicles {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr bool IsFront(int wheel) { return wheel < 2; }
constexpr bool IsLeft(int wheel) { return wheel % 2 == 0; }

// Bullet's default raycaster returns the closest hit, which can be the
// chassis itself when a suspension top lies inside the box; this one skips
// the chassis (and, like the default, bodies without contact response).
class WheelRaycaster : public btVehicleRaycaster {
 public:
  WheelRaycaster(btDynamicsWorld& world, const btCollisionObject& chassis) : world_(world), chassis_(chassis) {}

  void* castRay(const btVector3& from, const btVector3& to, btVehicleRaycasterResult& result) override {
    struct NotChassis : btCollisionWorld::ClosestRayResultCallback {
      NotChassis(const btVector3& a, const btVector3& b, const btCollisionObject& self)
          : ClosestRayResultCallback(a, b), self_(self) {}
      bool needsCollision(btBroadphaseProxy* proxy) const override {
        return proxy->m_clientObject != &self_ && ClosestRayResultCallback::needsCollision(proxy);
      }
      const btCollisionObject& self_;
    } callback(from, to, chassis_);
    world_.rayTest(from, to, callback);
    const btRigidBody* body = callback.hasHit() ? btRigidBody::upcast(callback.m_collisionObject) : nullptr;
    if (body == nullptr || !body->hasContactResponse()) return nullptr;
    result.m_hitPointInWorld = callback.m_hitPointWorld;
    result.m_hitNormalInWorld = callback.m_hitNormalWorld.normalized();
    result.m_distFraction = callback.m_closestHitFraction;
    return const_cast<btRigidBody*>(body);  // Bullet's interface hands out a mutable pointer
  }

 private:
  btDynamicsWorld& world_;
  const btCollisionObject& chassis_;
};

btRaycastVehicle::btVehicleTuning Tuning(const CarParams& p) {
  btRaycastVehicle::btVehicleTuning tuning;
  tuning.m_suspensionStiffness = btScalar(p.suspension_stiffness);
  tuning.m_suspensionCompression = btScalar(p.suspension_compression_damping);
  tuning.m_suspensionDamping = btScalar(p.suspension_relaxation_damping);
  tuning.m_maxSuspensionTravelCm = btScalar(p.max_suspension_travel * 100.0);
  tuning.m_frictionSlip = btScalar(p.friction_slip);
  tuning.m_maxSuspensionForce = btScalar(p.max_suspension_force);
  return tuning;
}

void CheckParams(const CarParams& p) {
  SIM4CV_THROW_UNLESS(p.mass > 0, "car mass " << p.mass << " must be > 0");
  SIM4CV_THROW_UNLESS(p.suspension_stiffness > 0, "suspension stiffness " << p.suspension_stiffness << " must be > 0");
  SIM4CV_THROW_UNLESS(StaticSuspensionLength(p) > 0,
                      "suspension rest length " << p.suspension_rest_length << " is shorter than the static sag");
  SIM4CV_THROW_UNLESS(p.max_steering_deg > 0 && p.max_steering_deg < 90,
                      "max steering " << p.max_steering_deg << " deg must be in (0, 90)");
  SIM4CV_THROW_UNLESS(p.max_steering_rate_deg > 0, "max steering rate " << p.max_steering_rate_deg << " must be > 0");
}

}  // namespace

btCollisionShape& Car::BuildChassisShape(btCompoundShape& compound, btBoxShape& box, const CarParams& params) {
  CheckParams(params);
  compound.addChildShape(
      btTransform(btQuaternion::getIdentity(), btVector3(0, 0, btScalar(params.center_of_mass_drop))), &box);
  return compound;
}

Car::Car(btDiscreteDynamicsWorld& world, const CarParams& params, const Eigen::Vector2d& position, double yaw,
         double ground_z)
    : params_(params),
      box_(ToBullet(params.chassis_half_extents)),
      chassis_(world, BuildChassisShape(compound_, box_, params_), params.mass, SpawnPose(position, yaw, ground_z)),
      raycaster_(std::make_unique<WheelRaycaster>(world, chassis_.body())),
      vehicle_(Tuning(params), &chassis_.body(), raycaster_.get()) {
  // Body axes: x forward, y left, z up (Bullet's indices: right, up, forward).
  // Bullet pushes a wheel along contact normal x axle, so the axle points
  // along -y for the engine to drive towards +x; suspensions point down.
  vehicle_.setCoordinateSystem(1, 2, 0);
  const btRaycastVehicle::btVehicleTuning tuning = Tuning(params_);
  for (int wheel = 0; wheel < kWheelCount; ++wheel) {
    const Eigen::Vector3d top(IsFront(wheel) ? params_.wheelbase / 2 : -params_.wheelbase / 2,
                              IsLeft(wheel) ? params_.track / 2 : -params_.track / 2, params_.suspension_top_z);
    btWheelInfo& info = vehicle_.addWheel(ToBullet(top + BoxCentreInBody()), btVector3(0, 0, -1), btVector3(0, -1, 0),
                                          btScalar(params_.suspension_rest_length), btScalar(params_.wheel_radius),
                                          tuning, IsFront(wheel));
    info.m_rollInfluence = btScalar(params_.roll_influence);
  }
  Reset(position, yaw, ground_z);
}

btTransform Car::SpawnPose(const Eigen::Vector2d& position, double yaw, double ground_z) const {
  const double box_centre_z = ground_z + BoxCentreHeightAtRest(params_);
  const btQuaternion rotation(btVector3(0, 0, 1), btScalar(yaw));
  const btVector3 box_centre(btScalar(position.x()), btScalar(position.y()), btScalar(box_centre_z));
  return btTransform(rotation, box_centre - btVector3(0, 0, btScalar(params_.center_of_mass_drop)));
}

void Car::Reset(const Eigen::Vector2d& position, double yaw, double ground_z) {
  chassis_.Teleport(SpawnPose(position, yaw, ground_z));
  vehicle_.resetSuspension();
  steering_angle_ = 0.0;
  controls_ = {};
  for (int wheel = 0; wheel < kWheelCount; ++wheel) vehicle_.setSteeringValue(0, wheel);
}

void Car::SetControls(const CarControls& controls) {
  controls_ = {std::clamp(controls.steering, -1.0, 1.0), std::clamp(controls.throttle, 0.0, 1.0),
               std::clamp(controls.brake, 0.0, 1.0), controls.reverse};
}

double Car::ForwardSpeed() const {
  const btRigidBody& body = chassis_.body();
  return body.getLinearVelocity().dot(body.getCenterOfMassTransform().getBasis().getColumn(0));
}

void Car::Update(double dt) {
  SIM4CV_DEMAND(dt > 0);
  // Steering: the wheel angle slews towards the command at a bounded rate.
  const double target = controls_.steering * params_.max_steering_deg * kDegToRad;
  const double max_change = params_.max_steering_rate_deg * kDegToRad * dt;
  steering_angle_ += std::clamp(target - steering_angle_, -max_change, max_change);
  // Bullet's wheel angle turns about +z, i.e. positive is to the left.
  for (int wheel = 0; wheel < kWheelCount; ++wheel) {
    if (IsFront(wheel)) vehicle_.setSteeringValue(btScalar(-steering_angle_), wheel);
  }

  // Brake beats throttle. At a crawl with the throttle released, a holding
  // brake stops the car for good: a free-rolling ray-cast car creeps on any
  // numerical imbalance.
  const double speed = ForwardSpeed();
  double brake = controls_.brake;
  if (controls_.throttle == 0.0 && std::abs(speed) < params_.hold_speed) brake = std::max(brake, params_.hold_brake);
  const double engine =
      brake > 0.0 ? 0.0
                  : controls_.throttle * (controls_.reverse ? -params_.max_reverse_force : params_.max_engine_force);
  // Bullet's "brake" is the most impulse the wheel may apply per step, N*s.
  const double brake_impulse_per_wheel = brake * params_.max_brake_force / kWheelCount * dt;
  for (int wheel = 0; wheel < kWheelCount; ++wheel) {
    vehicle_.applyEngineForce(IsFront(wheel) ? 0 : btScalar(engine / 2.0), wheel);
    vehicle_.setBrake(btScalar(brake_impulse_per_wheel), wheel);
  }

  // Rolling resistance and air drag oppose the forward motion.
  const double drag = -(params_.drag_linear * speed + params_.drag_quadratic * speed * std::abs(speed));
  btRigidBody& body = chassis_.body();
  body.applyCentralForce(body.getCenterOfMassTransform().getBasis().getColumn(0) * btScalar(drag));

  // The wheels' impulses go in before the step rather than from a world
  // action, which Bullet runs after integrating positions: then the velocity
  // read after a step would hold the next step's suspension impulse without
  // the gravity it balances (+g*dt = 4 cm/s upwards for a car at rest).
  vehicle_.updateVehicle(btScalar(dt));
}

VehicleState Car::State() const { return chassis_.StateAt(BoxCentreInBody()); }

Pose Car::WheelPose(int wheel) const {
  SIM4CV_DEMAND(wheel >= 0 && wheel < kWheelCount);
  const btWheelInfo& info = vehicle_.getWheelInfo(wheel);
  const btTransform& chassis = chassis_.body().getCenterOfMassTransform();
  const btVector3 down = chassis.getBasis() * btVector3(0, 0, -1);
  const btVector3 centre = chassis(info.m_chassisConnectionPointCS) + down * info.m_raycastInfo.m_suspensionLength;
  const double wheel_yaw = IsFront(wheel) ? -steering_angle_ : 0.0;
  return {FromBullet(centre), FromBullet(chassis.getRotation()) *
                                  Eigen::Quaterniond(Eigen::AngleAxisd(wheel_yaw, Eigen::Vector3d::UnitZ()))};
}

}  // namespace sim4cv::vehicles
