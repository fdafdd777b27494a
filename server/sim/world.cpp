#include "server/sim/world.h"

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <numbers>

#include "server/common/check.h"
#include "server/sim/controllers.h"
#include "server/sim/log/replay_track.h"
#include "server/sim/vehicles/car.h"
#include "server/sim/vehicles/car_driver.h"
#include "server/sim/vehicles/quadcopter.h"

namespace sim4cv::sim {
namespace {

void CopyState(const vehicles::VehicleState& in, BodyState& out) {
  out.position = in.position;
  out.orientation = in.orientation;
  out.linear_velocity = in.linear_velocity;
  out.angular_velocity = in.angular_velocity;
}

// A replayed body takes its logged state, or stays where it is, at rest.
void Follow(const BodyState* logged, BodyState& body) {
  if (logged) {
    body = *logged;
  } else {
    body.linear_velocity.setZero();
    body.angular_velocity.setZero();
  }
}

}  // namespace

struct World::Bodies {
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision_config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> statics;
  std::unique_ptr<vehicles::Car> car;
  std::unique_ptr<vehicles::CarDriver> driver;
  std::unique_ptr<vehicles::Quadcopter> uav;

  void AddStatic(std::unique_ptr<btCollisionShape> shape, const btTransform& pose) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape.get());
    info.m_startWorldTransform = pose;
    info.m_friction = 0.9;
    statics.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(shape));
    world.addRigidBody(statics.back().get());
  }

  ~Bodies() {
    car.reset();  // vehicles remove their own bodies and actions
    uav.reset();
    for (auto& body : statics) world.removeRigidBody(body.get());
  }
};

World::World(const Scene& scene)
    : scene_(scene),
      car_lane_(scene.car_lane),
      bodies_(std::make_unique<Bodies>()) {
  auto& b = *bodies_;
  b.world.setGravity(btVector3(0, 0, -9.81));
  b.AddStatic(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), btTransform::getIdentity());
  for (const auto& building : scene.buildings) {
    const btTransform pose(btQuaternion(btVector3(0, 0, 1), btScalar(building.yaw_deg * std::numbers::pi / 180.0)),
                           btVector3(building.centre.x(), building.centre.y(), building.height / 2.0f));
    b.AddStatic(std::make_unique<btBoxShape>(btVector3(building.half_size.x(), building.half_size.y(), building.height / 2.0f)),
                pose);
  }
  if (scene.map) {
    for (const auto& object : scene.map->objects) {
      if (object.kind == map::ObjectKind::kPark) continue;  // lawn and benches: nothing a car hits
      const map::ObjectShape& shape = map::ShapeOf(object.kind);
      const btTransform pose(btQuaternion(btVector3(0, 0, 1), btScalar(object.rotation_deg * std::numbers::pi / 180.0)),
                             btVector3(object.position.x(), object.position.y(), shape.height / 2.0));
      b.AddStatic(std::make_unique<btBoxShape>(btVector3(shape.half_x, shape.half_y, shape.height / 2.0)), pose);
    }
  }

  const Eigen::Vector2d start = car_lane_.PointAt(0.0);
  const Eigen::Vector2d tangent = car_lane_.TangentAt(0.0);
  b.car = std::make_unique<vehicles::Car>(b.world, scene.car.params, start, std::atan2(tangent.y(), tangent.x()));
  b.driver = std::make_unique<vehicles::CarDriver>(scene.car.params, vehicles::Polyline(car_lane_.points(), true),
                                                   scene.car.cruise_speed);
  BodyState car;
  CopyState(b.car->State(), car);
  const UavSetpoint station = FollowCar(scene.uav, scene.cameras.front().pitch_down_deg, car);
  b.uav = std::make_unique<vehicles::Quadcopter>(b.world, scene.uav.params, station.position, station.yaw);
  CopyState(b.car->State(), initial_state_.car);
  CopyState(b.uav->State(), initial_state_.uav);
}

World::~World() = default;

State World::InitialState() const { return initial_state_; }

void World::SetReplay(std::shared_ptr<const runlog::ReplayTrack> track) { replay_ = std::move(track); }

void World::Step(State& state, double dt) {
  SIM4CV_DEMAND(dt > 0);
  if (replay_) {
    FollowReplay(state);
  } else {
    StepPhysics(state, dt);
  }
  ++state.physics_steps;
  state.sim_time = static_cast<double>(state.physics_steps) * dt;
}

void World::FollowReplay(State& state) const {
  // Every substep of a frame looks up the same pose; the frame id is counted
  // by the caller after the frame's last substep.
  const uint64_t frame_id = state.frame_id + 1;
  Follow(replay_->Find(frame_id, kCarEntityId), state.car);
  Follow(replay_->Find(frame_id, kUavEntityId), state.uav);
}

void World::StepPhysics(State& state, double dt) {
  auto& b = *bodies_;
  vehicles::CarControls controls;
  if (state.car_command.manual) {
    controls = {state.car_command.steering, state.car_command.throttle, state.car_command.brake, false};
  } else {
    controls = b.driver->Update(b.car->State(), dt);
    state.car_command = {static_cast<float>(controls.steering), static_cast<float>(controls.throttle),
                         static_cast<float>(controls.brake), false};
  }
  b.car->SetControls(controls);
  b.car->Update(dt);

  // The camera UAV holds station behind and above the car; the car's
  // centripetal acceleration is fed forward so it does not lag in bends.
  const UavSetpoint station = FollowCar(scene_.uav, scene_.cameras.front().pitch_down_deg, state.car);
  const Eigen::Vector3d turn_acceleration = state.car.angular_velocity.cross(state.car.linear_velocity);
  b.uav->SetCommand(vehicles::QuadcopterCommand::Hold(station.position, station.yaw, station.velocity,
                                                      station.yaw_rate, turn_acceleration));
  b.uav->Update(dt);

  // maxSubSteps = 0: exactly one step of dt, no interpolation, so the result
  // depends only on the state and never on wall time.
  b.world.stepSimulation(dt, 0);
  CopyState(b.car->State(), state.car);
  CopyState(b.uav->State(), state.uav);
}

}  // namespace sim4cv::sim
