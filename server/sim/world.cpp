#include "server/sim/world.h"

#include <btBulletDynamicsCommon.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "server/common/check.h"
#include "server/sim/controllers.h"
#include "server/sim/entity_kind_registry.h"
#include "server/sim/track_servo.h"
#include "server/sim/log/replay_track.h"
#include "server/sim/traffic_bodies.h"
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

std::string_view KindName(EntityKind kind) { return InfoOf(kind).name; }

// The set speed a car (at most 40 m/s) or a pedestrian (10 m/s) may be given.
void CheckSpeed(EntityKind kind, float speed) {
  const bool walking = kind == EntityKind::kPedestrian;
  const float most = walking ? 10.0f : 40.0f;
  SIM4CV_THROW_UNLESS(std::isfinite(speed) && speed >= 0 && speed <= most,
                      (walking ? "walking" : "car") << " speed " << speed << " m/s is outside [0, " << most << "]");
}

// A pedestrian's pose and velocity `walked` metres along its route.
void PlaceWalker(const vehicles::Polyline& route, double walked, double speed, BodyState& body) {
  const double step = 0.05;  // m: the heading from a short chord, defined at any point
  const Eigen::Vector2d here = route.PointAt(walked);
  Eigen::Vector2d ahead = route.PointAt(walked + step) - here;
  if (ahead.squaredNorm() < 1e-12) ahead = here - route.PointAt(walked - step);
  const double heading = std::atan2(ahead.y(), ahead.x());
  body.position = {here.x(), here.y(), 0.0};
  body.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()));
  body.linear_velocity = Eigen::Vector3d(std::cos(heading), std::sin(heading), 0.0) * speed;
  body.angular_velocity.setZero();
}

}  // namespace

std::string EntityList(const State& state) {
  std::ostringstream list;
  for (const Entity& entity : state.entities) {
    list << (&entity == &state.entities.front() ? "" : ", ") << entity.id << " ('" << entity.name << "', "
         << KindName(entity.kind) << ")";
  }
  return state.entities.empty() ? "none" : list.str();
}

// The Bullet side of one entity, in the same order as State::entities.
struct World::Vehicle {
  uint32_t id = 0;
  std::unique_ptr<vehicles::Car> car;
  std::unique_ptr<vehicles::CarDriver> driver;  // null: no route, the car waits for Controls
  std::unique_ptr<vehicles::Quadcopter> uav;
  std::unique_ptr<vehicles::Polyline> walk;  // a pedestrian's route; null: it stands
};

struct World::Bodies {
  btDefaultCollisionConfiguration collision_config;
  btCollisionDispatcher dispatcher{&collision_config};
  btDbvtBroadphase broadphase;
  btSequentialImpulseConstraintSolver solver;
  btDiscreteDynamicsWorld world{&dispatcher, &broadphase, &solver, &collision_config};
  std::vector<std::unique_ptr<btCollisionShape>> shapes;
  std::vector<std::unique_ptr<btRigidBody>> statics;
  std::vector<Vehicle> vehicles;  // ordered by id, like State::entities

  void AddStatic(std::unique_ptr<btCollisionShape> shape, const btTransform& pose) {
    btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape.get());
    info.m_startWorldTransform = pose;
    info.m_friction = 0.9;
    statics.push_back(std::make_unique<btRigidBody>(info));
    shapes.push_back(std::move(shape));
    world.addRigidBody(statics.back().get());
  }

  ~Bodies() {
    vehicles.clear();  // vehicles remove their own bodies and actions
    for (auto& body : statics) world.removeRigidBody(body.get());
  }
};

World::World(const Scene& scene) : scene_(scene), car_lane_(scene.car_lane, /*closed=*/true), bodies_(std::make_unique<Bodies>()) {
  auto& b = *bodies_;
  b.world.setGravity(btVector3(0, 0, -9.81));
  b.AddStatic(std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), 0), btTransform::getIdentity());
  for (const auto& building : scene.buildings) {
    const btTransform pose(btQuaternion(btVector3(0, 0, 1), btScalar(building.yaw_deg * std::numbers::pi / 180.0)),
                           btVector3(building.centre.x(), building.centre.y(), building.height / 2.0f));
    b.AddStatic(
        std::make_unique<btBoxShape>(btVector3(building.half_size.x(), building.half_size.y(), building.height / 2.0f)),
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

  // The scene's own entities: the target car on its lane and the camera UAV filming it.
  const Eigen::Vector2d start = car_lane_.PointAt(0.0);
  const Eigen::Vector2d tangent = car_lane_.TangentAt(0.0);
  const double car_yaw = std::atan2(tangent.y(), tangent.x());
  SIM4CV_DEMAND(Spawn(initial_state_, EntityKind::kCar, scene.car.name, {{start.x(), start.y(), 0.0}, car_yaw}) ==
                kCarEntityId);
  SetRoute(initial_state_, kCarEntityId, car_lane_.points(), true, scene.car.cruise_speed);
  UavOrder follow;
  follow.target = kCarEntityId;
  follow.altitude = scene.uav.altitude;
  const int uav_camera = scene.FindCamera("uav");
  follow.pitch_down_deg = uav_camera >= 0 ? scene.cameras[uav_camera].pitch_down_deg : 60.0;
  const UavSetpoint station = FollowTarget(follow, initial_state_.entities.front().body);
  SIM4CV_DEMAND(Spawn(initial_state_, EntityKind::kUav, scene.uav.name, {station.position, station.yaw}) ==
                kUavEntityId);
  SetUavOrder(initial_state_, kUavEntityId, follow);
  if (scene.traffic) initial_state_.traffic = traffic::InitialTraffic(*scene.traffic);
  traffic_ids_ = TrafficIdsOf(scene);
}

World::~World() = default;

State World::InitialState() const { return initial_state_; }

void World::SetReplay(std::shared_ptr<const runlog::ReplayTrack> track, std::vector<uint32_t> only) {
  replay_ = std::move(track);
  std::sort(only.begin(), only.end());
  replay_only_ = std::move(only);
}

bool World::Replayed(uint32_t id) const {
  return replay_ && (replay_only_.empty() || std::binary_search(replay_only_.begin(), replay_only_.end(), id));
}

uint32_t World::Spawn(State& state, EntityKind kind, const std::string& name, const SpawnPose& pose) {
  SIM4CV_THROW_UNLESS(pose.position.allFinite() && std::isfinite(pose.yaw),
                      "spawn pose (" << pose.position.transpose() << ", yaw " << pose.yaw << ") is not finite");
  SIM4CV_THROW_UNLESS(kind != EntityKind::kUav || pose.position.z() >= 0.5,
                      "a UAV must spawn in the air; z is " << pose.position.z() << " m (at least 0.5)");
  uint32_t id = 1;
  for (const Entity& entity : state.entities) {  // ordered by id: the first gap is the lowest free id
    if (entity.id != id) break;
    ++id;
  }
  SIM4CV_THROW_UNLESS(id <= kMaxEntityId, "the world already holds " << kMaxEntityId << " entities, the most it can");
  const EntityKindEntry* registered = FindRegisteredKind(kind);
  const std::string entity_name = name.empty() ? std::string(kind == EntityKind::kCar   ? "car_"
                                                            : kind == EntityKind::kUav ? "uav_"
                                                            : registered ? std::string(registered->info.name) + "_"
                                                                         : "pedestrian_") +
                                                    std::to_string(id)
                                              : name;
  SIM4CV_THROW_UNLESS(!state.FindByName(entity_name), "an entity named '" << entity_name << "' already exists");

  auto& b = *bodies_;
  Vehicle vehicle;
  vehicle.id = id;
  Entity entity;
  entity.id = id;
  entity.kind = kind;
  entity.name = entity_name;
  if (kind == EntityKind::kCar) {
    vehicle.car = std::make_unique<vehicles::Car>(b.world, scene_.car.params, pose.position.head<2>(), pose.yaw);
    CopyState(vehicle.car->State(), entity.body);
    entity.car_command = {0.0f, 0.0f, 1.0f, true};  // parked until told otherwise
  } else if (kind == EntityKind::kPedestrian) {
    // Kinematic: no Bullet body, it stands on the ground where it is put.
    entity.body.position = {pose.position.x(), pose.position.y(), 0.0};
    entity.body.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()));
  } else if (registered) {
    registered->behaviour->Spawn(pose.position, pose.yaw, entity);  // kinematic too: no Bullet body
  } else {
    vehicle.uav = std::make_unique<vehicles::Quadcopter>(b.world, scene_.uav.params, pose.position, pose.yaw);
    CopyState(vehicle.uav->State(), entity.body);
    entity.uav_order.mode = UavOrder::Mode::kHold;
    entity.uav_order.position = pose.position;
    entity.uav_order.yaw = pose.yaw;
  }
  const auto at = std::lower_bound(state.entities.begin(), state.entities.end(), id,
                                   [](const Entity& a, uint32_t wanted) { return a.id < wanted; });
  const auto index = at - state.entities.begin();
  state.entities.insert(at, std::move(entity));
  b.vehicles.insert(b.vehicles.begin() + index, std::move(vehicle));
  return id;
}

World::Vehicle& World::VehicleOf(const State& state, uint32_t id, EntityKind kind, const char* what) {
  const Entity* entity = state.Find(id);
  SIM4CV_THROW_UNLESS(entity, what << ": no entity has id " << id << "; the world holds " << EntityList(state));
  SIM4CV_THROW_UNLESS(entity->kind == kind, what << ": entity " << id << " ('" << entity->name << "') is a "
                                                << KindName(entity->kind) << ", not a " << KindName(kind));
  auto& vehicles = bodies_->vehicles;
  const auto it = std::lower_bound(vehicles.begin(), vehicles.end(), id,
                                   [](const Vehicle& v, uint32_t wanted) { return v.id < wanted; });
  SIM4CV_DEMAND(it != vehicles.end() && it->id == id);
  return *it;
}

void World::Remove(State& state, uint32_t id) {
  const Entity* entity = state.Find(id);
  SIM4CV_THROW_UNLESS(entity, "Remove: no entity has id " << id << "; the world holds " << EntityList(state));
  VehicleOf(state, id, entity->kind, "Remove");
  const auto index = entity - state.entities.data();
  state.entities.erase(state.entities.begin() + index);
  bodies_->vehicles.erase(bodies_->vehicles.begin() + index);
  for (Entity& other : state.entities) {
    if (other.kind == EntityKind::kUav && other.uav_order.mode == UavOrder::Mode::kFollow &&
        other.uav_order.target == id) {
      other.uav_order.mode = UavOrder::Mode::kHold;
      other.uav_order.position = other.body.position;
      other.uav_order.yaw = other.body.Yaw();
    }
  }
}

void World::SetRoute(State& state, uint32_t id, std::vector<Eigen::Vector2d> path, bool closed, float speed) {
  const Entity* found = state.Find(id);
  if (found && found->kind == EntityKind::kPedestrian) return SetWalk(state, id, std::move(path), closed, speed);
  Vehicle& vehicle = VehicleOf(state, id, EntityKind::kCar, "SetRoute");
  CheckSpeed(EntityKind::kCar, speed);
  SIM4CV_THROW_UNLESS(path.size() >= 2, "a route needs at least 2 points; got " << path.size());
  vehicle.driver =
      std::make_unique<vehicles::CarDriver>(scene_.car.params, vehicles::Polyline(std::move(path), closed), speed);
  Entity& entity = *state.Find(id);
  entity.cruise_speed = speed;
  entity.car_command.manual = false;
}

void World::SetWalk(State& state, uint32_t id, std::vector<Eigen::Vector2d> path, bool closed, float speed) {
  Vehicle& vehicle = VehicleOf(state, id, EntityKind::kPedestrian, "SetRoute");
  CheckSpeed(EntityKind::kPedestrian, speed);
  SIM4CV_THROW_UNLESS(path.size() >= (closed ? 3u : 2u),
                      "a walking route needs at least " << (closed ? 3 : 2) << " points; got " << path.size());
  vehicle.walk = std::make_unique<vehicles::Polyline>(std::move(path), closed);
  Entity& entity = *state.Find(id);
  entity.cruise_speed = speed;
  entity.walked = 0.0;  // from the route's start, where it is put at once
  PlaceWalker(*vehicle.walk, entity.walked, speed, entity.body);
}

void World::SetCruiseSpeed(State& state, uint32_t id, float speed) {
  const Entity* found = state.Find(id);
  if (found && found->kind == EntityKind::kPedestrian) {
    Vehicle& walker = VehicleOf(state, id, EntityKind::kPedestrian, "SetSpeed");
    SIM4CV_THROW_UNLESS(walker.walk, "pedestrian " << id << " has no route to walk at " << speed << " m/s");
    CheckSpeed(EntityKind::kPedestrian, speed);
    state.Find(id)->cruise_speed = speed;
    return;
  }
  Vehicle& vehicle = VehicleOf(state, id, EntityKind::kCar, "SetSpeed");
  CheckSpeed(EntityKind::kCar, speed);
  SIM4CV_THROW_UNLESS(vehicle.driver, "car " << id << " has no route to drive at " << speed
                                             << " m/s; give it one (SetRoute) or drive it with Controls");
  vehicle.driver->set_speed(speed);
  Entity& entity = *state.Find(id);
  entity.cruise_speed = speed;
  entity.car_command.manual = false;
}

void World::SetUavOrder(State& state, uint32_t id, const UavOrder& order) {
  VehicleOf(state, id, EntityKind::kUav, "CommandUav");
  if (order.mode == UavOrder::Mode::kFollow) {
    const Entity* target = state.Find(order.target);
    SIM4CV_THROW_UNLESS(target && order.target != id, "UAV " << id << " cannot follow entity " << order.target
                                                             << "; the world holds " << EntityList(state));
  }
  state.Find(id)->uav_order = order;
}

void World::Step(State& state, double dt) {
  SIM4CV_DEMAND(dt > 0);
  // Traffic first, from the entities' poses at the step's start, so the cars
  // below see where the traffic will be and the order is fixed. A whole
  // replay takes the traffic from the log too.
  if (!replay_ || !replay_only_.empty()) StepTraffic(state, dt);
  if (replay_ && replay_only_.empty()) {
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
  for (Entity& entity : state.entities) Follow(replay_->Find(frame_id, entity.id), entity.body);
  // Traffic the log holds is put where it was; the rest stands, at rest.
  auto& traffic = state.traffic;
  for (std::size_t i = 0; i < traffic.cars.size(); ++i) {
    BodyState body = BodyOf(traffic.cars[i]);
    Follow(replay_->Find(frame_id, traffic_ids_.cars + static_cast<uint32_t>(i)), body);
    PlaceAt(body, traffic.cars[i]);
  }
  for (std::size_t i = 0; i < traffic.walkers.size(); ++i) {
    BodyState body = BodyOf(traffic.walkers[i]);
    Follow(replay_->Find(frame_id, traffic_ids_.walkers + static_cast<uint32_t>(i)), body);
    PlaceAt(body, traffic.walkers[i]);
  }
}

void World::StepPhysics(State& state, double dt) {
  auto& b = *bodies_;
  SIM4CV_DEMAND(b.vehicles.size() == state.entities.size());
  for (std::size_t i = 0; i < state.entities.size(); ++i) {
    Entity& entity = state.entities[i];
    Vehicle& vehicle = b.vehicles[i];
    SIM4CV_ASSERT(vehicle.id == entity.id);
    if (Replayed(entity.id)) {
      Follow(replay_->Find(state.frame_id + 1, entity.id), entity.body);
      if (vehicle.car) {
        vehicle.car->Reset(entity.body.position.head<2>(), entity.body.Yaw());
      } else if (vehicle.uav) {
        vehicle.uav->Reset(entity.body.position, entity.body.Yaw());
      }
      continue;
    }
    if (entity.kind == EntityKind::kPedestrian) {
      StepWalker(vehicle, entity, dt);
      continue;
    }
    if (!vehicle.car && !vehicle.uav) {  // a registered kind's (entity_kind_registry.h)
      FindRegisteredKind(entity.kind)->behaviour->Step(entity, state, dt);
      continue;
    }
    if (vehicle.car) {
      vehicles::CarControls controls;
      if (entity.car_command.manual || !vehicle.driver) {
        const CarCommand& c = entity.car_command;
        controls = {c.steering, c.throttle, c.brake, false};
      } else {
        if (AnythingToGiveWayTo(state))
          vehicle.driver->set_speed(SpeedForTraffic(state, entity, vehicle.driver->path()));
        controls = vehicle.driver->Update(vehicle.car->State(), dt);
        entity.car_command = {static_cast<float>(controls.steering), static_cast<float>(controls.throttle),
                             static_cast<float>(controls.brake), false};
      }
      vehicle.car->SetControls(controls);
      vehicle.car->Update(dt);
    } else {
      vehicle.uav->SetCommand(entity.uav_order.mode == UavOrder::Mode::kTrack
                                  ? TrackCommand(entity.uav_order, entity.id, entity.body, state)
                                  : UavCommandFor(entity.uav_order, entity.body, state));
      vehicle.uav->Update(dt);
    }
  }
  // maxSubSteps = 0: exactly one step of dt, no interpolation, so the result
  // depends only on the state and never on wall time.
  b.world.stepSimulation(dt, 0);
  for (std::size_t i = 0; i < state.entities.size(); ++i) {
    const Vehicle& vehicle = b.vehicles[i];
    if (Replayed(vehicle.id) || (!vehicle.car && !vehicle.uav)) continue;  // kinematic: State holds its body
    CopyState(vehicle.car ? vehicle.car->State() : vehicle.uav->State(), state.entities[i].body);
  }
}

void World::StepWalker(const Vehicle& vehicle, Entity& walker, double dt) {
  if (!vehicle.walk) return;
  const vehicles::Polyline& route = *vehicle.walk;
  const double end = route.length();
  double speed = walker.cruise_speed;
  walker.walked += speed * dt;
  if (route.closed()) {
    walker.walked = std::fmod(walker.walked, end);
  } else if (walker.walked >= end) {
    walker.walked = end;  // arrived: it stands at the end
    speed = 0.0;
  }
  PlaceWalker(route, walker.walked, speed, walker.body);
}

}  // namespace sim4cv::sim
