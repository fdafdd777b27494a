#include "server/sim/world.h"

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <numbers>

#include "server/common/check.h"
#include "server/sim/controllers.h"

namespace sim4cv::sim {
namespace {

std::vector<Eigen::Vector2d> ToDouble(const std::vector<Eigen::Vector2f>& points) {
  std::vector<Eigen::Vector2d> out;
  out.reserve(points.size());
  for (const auto& p : points) out.push_back(p.cast<double>());
  return out;
}

btVector3 ToBullet(const Eigen::Vector3d& v) { return btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())); }
Eigen::Vector3d FromBullet(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

void ReadBody(const btRigidBody& body, BodyState& out) {
  const btTransform& t = body.getCenterOfMassTransform();
  out.position = FromBullet(t.getOrigin());
  const btQuaternion q = t.getRotation();
  out.orientation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
  out.linear_velocity = FromBullet(body.getLinearVelocity());
  out.angular_velocity = FromBullet(body.getAngularVelocity());
}

void WriteBody(const BodyState& in, btRigidBody& body) {
  btTransform t;
  t.setOrigin(ToBullet(in.position));
  t.setRotation(btQuaternion(in.orientation.x(), in.orientation.y(), in.orientation.z(), in.orientation.w()));
  body.setCenterOfMassTransform(t);
  body.setLinearVelocity(ToBullet(in.linear_velocity));
  body.setAngularVelocity(ToBullet(in.angular_velocity));
}

// Gains of the simplified car model (a sliding box steered by forces; the
// full btRaycastVehicle arrives with the world issue).
constexpr double kLateralGrip = 12.0;    // 1/s: how fast sideways slip is killed
constexpr double kYawTracking = 12.0;    // 1/s: how fast yaw rate follows steering
constexpr double kRollingDrag = 0.05;    // 1/s
// Gains of the camera UAV's station keeping (critically damped, 1 s).
constexpr double kUavPositionGain = 4.0;  // 1/s^2
constexpr double kUavVelocityGain = 4.0;  // 1/s
constexpr double kUavYawGain = 6.0;

}  // namespace

struct World::Bullet {
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision_config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btDefaultMotionState>> motion_states;
  std::vector<std::unique_ptr<btRigidBody>> bodies;
  btRigidBody* car = nullptr;
  btRigidBody* uav = nullptr;

  btRigidBody* AddBody(std::unique_ptr<btCollisionShape> shape, double mass, const btTransform& pose, double friction) {
    btVector3 inertia(0, 0, 0);
    if (mass > 0) shape->calculateLocalInertia(mass, inertia);
    motion_states.push_back(std::make_unique<btDefaultMotionState>(pose));
    btRigidBody::btRigidBodyConstructionInfo info(mass, motion_states.back().get(), shape.get(), inertia);
    info.m_friction = friction;
    bodies.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(shape));
    world.addRigidBody(bodies.back().get());
    return bodies.back().get();
  }

  ~Bullet() {
    for (auto& body : bodies) world.removeRigidBody(body.get());
  }
};

World::World(const Scene& scene)
    : scene_(scene),
      car_lane_(ClosedPath::Offset(ToDouble(scene.road_loop), scene.lane_width / 2.0)),
      bullet_(std::make_unique<Bullet>()) {
  auto& b = *bullet_;
  b.world.setGravity(btVector3(0, 0, -9.81));
  b.AddBody(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), 0, btTransform::getIdentity(), 0.0);
  for (const auto& building : scene.buildings) {
    btTransform pose(btQuaternion(btVector3(0, 0, 1), building.yaw_deg * std::numbers::pi / 180.0),
                     btVector3(building.centre.x(), building.centre.y(), building.height / 2.0));
    b.AddBody(std::make_unique<btBoxShape>(btVector3(building.half_size.x(), building.half_size.y(), building.height / 2.0)),
              0, pose, 0.5);
  }
  const CarSpec& car = scene.car;
  // Frictionless contact: the car model sets its own longitudinal and lateral forces.
  b.car = b.AddBody(std::make_unique<btBoxShape>(btVector3(car.length / 2, car.width / 2, car.height / 2)), car.mass,
                    btTransform::getIdentity(), 0.0);
  b.car->setAngularFactor(btVector3(0, 0, 1));  // no roll or pitch in the simplified model
  b.car->setActivationState(DISABLE_DEACTIVATION);
  const double uav_half = scene.uav.span / 2.0;
  b.uav = b.AddBody(std::make_unique<btBoxShape>(btVector3(uav_half, uav_half, 0.1)), scene.uav.mass,
                    btTransform::getIdentity(), 0.0);
  b.uav->setGravity(btVector3(0, 0, 0));  // it hovers; the quadcopter model with thrust comes later
  b.uav->setAngularFactor(btVector3(0, 0, 1));
  b.uav->setActivationState(DISABLE_DEACTIVATION);
  // Bodies hold their state in State; World writes it in before each step.
  b.uav->setCollisionFlags(b.uav->getCollisionFlags() | btCollisionObject::CF_NO_CONTACT_RESPONSE);
}

World::~World() = default;

State World::InitialState() const {
  State state;
  const Eigen::Vector2d start = car_lane_.PointAt(0.0);
  const Eigen::Vector2d tangent = car_lane_.TangentAt(0.0);
  const double yaw = std::atan2(tangent.y(), tangent.x());
  state.car.position = {start.x(), start.y(), scene_.car.height / 2.0};
  state.car.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  const UavSetpoint station = FollowCar(scene_.uav, scene_.cameras.front().pitch_down_deg, state.car);
  state.uav.position = station.position;
  state.uav.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(station.yaw, Eigen::Vector3d::UnitZ()));
  return state;
}

void World::ApplyCarForces(const State& state, double dt) {
  const CarSpec& spec = scene_.car;
  const BodyState& car = state.car;
  const double yaw = car.Yaw();
  const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
  const Eigen::Vector3d left(-std::sin(yaw), std::cos(yaw), 0.0);
  const double forward_speed = car.linear_velocity.dot(forward);
  const double lateral_speed = car.linear_velocity.dot(left);
  const CarCommand& command = state.car_command;

  double accel = command.throttle * spec.max_accel - kRollingDrag * forward_speed;
  // Braking opposes motion but never reverses it within one step.
  const double brake = command.brake * spec.max_brake_decel;
  if (std::abs(forward_speed) > 1e-3) accel -= std::copysign(std::min(brake, std::abs(forward_speed) / dt), forward_speed);
  const Eigen::Vector3d force = spec.mass * (accel * forward - kLateralGrip * lateral_speed * left);
  bullet_->car->applyCentralForce(ToBullet(force));

  const double steer = -command.steering * spec.max_steer_deg * std::numbers::pi / 180.0;
  const double wanted_yaw_rate = forward_speed * std::tan(steer) / spec.wheelbase;
  const double inertia_z = 1.0 / bullet_->car->getInvInertiaDiagLocal().z();
  const double torque = inertia_z * kYawTracking * (wanted_yaw_rate - car.angular_velocity.z());
  bullet_->car->applyTorque(btVector3(0, 0, torque));
}

void World::ApplyUavForces(const State& state) {
  const UavSetpoint setpoint = FollowCar(scene_.uav, scene_.cameras.front().pitch_down_deg, state.car);
  const BodyState& uav = state.uav;
  const Eigen::Vector3d accel = kUavPositionGain * (setpoint.position - uav.position) +
                                kUavVelocityGain * (setpoint.velocity - uav.linear_velocity);
  bullet_->uav->applyCentralForce(ToBullet(scene_.uav.mass * accel));
  const double inertia_z = 1.0 / bullet_->uav->getInvInertiaDiagLocal().z();
  const double yaw_accel = kUavYawGain * kUavYawGain / 4.0 * WrapAngle(setpoint.yaw - uav.Yaw()) +
                           kUavYawGain * (setpoint.yaw_rate - uav.angular_velocity.z());
  bullet_->uav->applyTorque(btVector3(0, 0, inertia_z * yaw_accel));
}

void World::Step(State& state, double dt) {
  SIM4CV_DEMAND(dt > 0);
  if (!state.car_command.manual) state.car_command = FollowLane(scene_.car, car_lane_, state.car);
  WriteBody(state.car, *bullet_->car);
  WriteBody(state.uav, *bullet_->uav);
  ApplyCarForces(state, dt);
  ApplyUavForces(state);
  // maxSubSteps = 0: exactly one step of dt, no interpolation, so the result
  // depends only on the state and never on wall time.
  bullet_->world.stepSimulation(dt, 0);
  bullet_->world.clearForces();
  ReadBody(*bullet_->car, state.car);
  ReadBody(*bullet_->uav, state.uav);
  ++state.physics_steps;
  state.sim_time = static_cast<double>(state.physics_steps) * dt;
}

}  // namespace sim4cv::sim
