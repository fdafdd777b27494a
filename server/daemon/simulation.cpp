#include "server/daemon/simulation.h"

#include <cmath>
#include <filesystem>
#include <numbers>

#include "server/common/check.h"
#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/daemon/configure_request.h"
#include "server/daemon/named_files.h"
#include "server/daemon/run_logger.h"
#include "server/wire/effects_wire.h"
#include "server/sim/map/map_text.h"

namespace sim4cv::daemon {
namespace {

constexpr double kDegrees = std::numbers::pi / 180.0;
using limits::kMaxCameraIndices;
using limits::kMaxCameras;

double Degrees(double radians) { return radians / kDegrees; }

void SetLanePoint(const map::LanePoint& lane, proto::LanePoint& out) {
  out.mutable_position()->set_x(lane.position.x());
  out.mutable_position()->set_y(lane.position.y());
  out.set_heading_deg(Degrees(lane.heading));
  out.set_segment(lane.segment);
  out.set_s(lane.s);
}

// Runs `action`, turning the World's std::invalid_argument into the Error
// a client gets.
template <typename Action>
auto Checked(Action&& action) {
  try {
    return action();
  } catch (const std::invalid_argument& error) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, error.what());
  }
}

}  // namespace

Simulation::Simulation(const Config& config, std::shared_ptr<const sim::Scene> scene)
    : config_(config),
      conditions_(config.conditions),
      effects_(config.effects),
      randomize_seed_(config.randomize_seed),
      randomize_every_(config.randomize_every_frames),
      log_file_(config.log_file) {
  if (!config.replay_file.empty()) replay_ = LoadReplayTrack(config, *scene);
  Change ignored;
  Rebuild(std::move(scene), ignored);
  Commit();
}

void Simulation::Commit() {
  replaced_.reset();
  camera_added_ = false;
}

void Simulation::Undo() {
  if (replaced_) {
    scene_ = std::move(replaced_->scene);
    world_ = std::move(replaced_->world);
    state_ = std::move(replaced_->state);
    cameras_ = std::move(replaced_->cameras);
    conditions_ = replaced_->conditions;
    episodes_ = replaced_->episodes;
  } else if (camera_added_) {
    cameras_.pop_back();
  }
  Commit();
}

int Simulation::FindCamera(const std::string& name) const {
  if (name.empty()) return -1;
  for (std::size_t i = 0; i < cameras_.size(); ++i) {
    if (cameras_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

void Simulation::Rebuild(std::shared_ptr<const sim::Scene> scene, Change& change) {
  // Everything new is built before anything old is touched, so a throw
  // (std::invalid_argument from a pose, std::bad_alloc) leaves the old world
  // in place; the old one is kept until Commit() for Undo().
  auto world = std::make_unique<sim::World>(*scene);
  if (replay_) world->SetReplay(replay_, config_.replay_only);
  sim::State state = world->InitialState();
  std::vector<sim::CameraSpec> cameras = scene->cameras;
  replaced_.emplace(
      Replaced{std::move(scene_), std::move(world_), std::move(state_), std::move(cameras_), conditions_, episodes_});
  world_ = std::move(world);
  scene_ = std::move(scene);
  state_ = std::move(state);
  cameras_ = std::move(cameras);
  change.new_scene = true;
  StartEpisode(change);
}

// Per-episode randomisation draws episode k's conditions at the start of
// episode k (the daemon's start is episode 0); per-N-frames draws frame 0's.
void Simulation::StartEpisode(Change& change) {
  ++episodes_;
  if (randomize_seed_ == 0) return;
  DrawConditions();
  change.new_conditions = true;
}

bool Simulation::AdvanceConditions() {
  if (randomize_seed_ == 0 || randomize_every_ == 0 || state_.frame_id % randomize_every_ != 0) return false;
  DrawConditions();
  return true;
}

// The draw of the randomisation in force for now: this episode's (the
// episodes begun, less one), or that of the block of randomize_every_
// frames the state is in. Keeps the quality and sensor noise.
void Simulation::DrawConditions() {
  const uint64_t draw = randomize_every_ == 0 ? episodes_ - 1 : state_.frame_id / randomize_every_;
  conditions_ = conditions::Randomized(randomize_seed_, draw, conditions_);
}

Simulation::Change Simulation::Apply(const proto::Configure& request, proto::Configured& answer) {
  using Kind = proto::Configure::RequestCase;
  Commit();  // an Apply can be undone only until the next one
  Change change;
  answer.set_request_id(request.request_id());
  switch (request.request_case()) {
    case Kind::kLoadMap:
      LoadMap(request.load_map(), change);
      break;
    case Kind::kReset:
      RefuseWhileLogging("Reset", "a log's frame ids must increase");
      Rebuild(scene_, change);
      break;
    case Kind::kSpawn:
      answer.set_entity_id(Spawn(request.spawn()));
      break;
    case Kind::kRemove:
      RemoveEntity(request.remove().entity_id(), change);
      break;
    case Kind::kSetRoute:
      SetRoute(request.set_route());
      break;
    case Kind::kCommandUav:
      CommandUav(request.command_uav());
      break;
    case Kind::kAddCamera:
      AddCamera(request.add_camera());
      break;
    case Kind::kRemoveCamera:
      RemoveCamera(request.remove_camera().name(), change);
      break;
    case Kind::kSetCameraPose:
      SetCameraPose(request.set_camera_pose());
      break;
    case Kind::kQueryRoad:
      QueryRoad(request.query_road(), *answer.mutable_road());
      change.world_changed = false;
      break;
    case Kind::kListMaps:
    case Kind::kCheckMap:
    case Kind::kGenerateMap:
    case Kind::kOpenMap:
    case Kind::kSaveMap:
    case Kind::kStartLog:
    case Kind::kStopLog:
      // The sim thread's: the log is its own (SimThread::ConfigureLog); authoring goes to its AuthoringWorker.
      SIM4CV_DEMAND(false);
      break;
    case Kind::kSetConditions:
      SetConditions(request.set_conditions(), change);
      break;
    case Kind::kSetEffects:
      SetEffects(request.set_effects(), change);
      break;
    case Kind::REQUEST_NOT_SET:
      throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "Configure carries no request");
    default:  // a request with a file of its own (configure_requests.cpp)
      const ConfigureRequest* carried = FindConfigureRequest(request.request_case());
      if (carried == nullptr) {
        throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT,
                             "Configure request " + std::to_string(request.request_case()) +
                                 " is not carried out by this daemon");
      }
      carried->apply(*this, request, answer, change);
      break;
  }
  try {
    FillWorldInfo(*answer.mutable_world());
  } catch (...) {
    Undo();  // no half-carried-out LoadMap, Reset or AddCamera
    throw;
  }
  return change;
}

void Simulation::LoadMap(const proto::LoadMap& load, Change& change) {
  RefuseWhileLogging("LoadMap", "a log holds one map");
  if (!config_.replay_file.empty()) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_STATE, "LoadMap is refused while the daemon replays --replay " +
                                                              config_.replay_file +
                                                              ": the log was recorded on this map; start another "
                                                              "sim4cvd for another map");
  }
  std::shared_ptr<const map::Map> loaded;
  if (load.has_name()) {
    // Read beneath --maps-dir with no link followed, like OpenMap; a parse
    // error names the map, not where a link might have led.
    const std::string text = ReadMapFile(config_.maps_dir, load.name(), "LoadMap.name");
    loaded = Checked([&] {
      try {
        return std::make_shared<const map::Map>(map::ParseMap(text));
      } catch (const std::invalid_argument& error) {
        throw std::invalid_argument("LoadMap.name " + Quoted(load.name()) + ": " + error.what());
      }
    });
  } else {
    loaded = Checked([&] {
      try {
        return std::make_shared<const map::Map>(map::ParseMap(load.text()));
      } catch (const std::invalid_argument& error) {
        throw std::invalid_argument(std::string("LoadMap.text: ") + error.what());
      }
    });
  }
  const float speed = load.car_speed() > 0 ? load.car_speed() : config_.car_speed;
  auto scene = Checked([&] {
    sim::Scene built = sim::SceneFromMap(std::move(loaded), load.route(), speed, config_.width, config_.height);
    if (load.has_name()) built.map_path = config_.maps_dir + "/" + load.name() + ".map";
    try {
      sim::AddTraffic(built, TrafficFor(load));
    } catch (const std::invalid_argument& error) {
      // The plan names the daemon flag; say where this request's numbers came from.
      throw std::invalid_argument(
          std::string(load.has_traffic() ? "LoadMap.traffic: " : "the daemon's traffic flags: ") + error.what());
    }
    return std::make_shared<const sim::Scene>(std::move(built));
  });
  Rebuild(std::move(scene), change);
}

traffic::TrafficConfig Simulation::TrafficFor(const proto::LoadMap& load) const {
  traffic::TrafficConfig traffic = config_.traffic;  // the daemon's --traffic-* flags, unless the request says
  if (!load.has_traffic()) return traffic;
  const proto::TrafficSettings& asked = load.traffic();
  traffic.moving_cars = static_cast<int>(asked.cars());
  traffic.parked_cars = static_cast<int>(asked.parked());
  traffic.pedestrians = static_cast<int>(asked.pedestrians());
  traffic.traffic_lights = !asked.no_lights();
  if (asked.seed() != 0) traffic.seed = asked.seed();
  return traffic;
}

void Simulation::RefuseWhileLogging(const char* request, const char* why) const {
  if (log_file_.empty()) return;
  const bool started = config_.log_file.empty();  // by a client's StartLog, not --log
  throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                       std::string(request) + " is refused while the daemon writes the run log " +
                           (started ? "" : "--log ") + log_file_ + ": " + why +
                           (started ? "; StopLog first" : "; start another sim4cvd without --log for this"));
}

const sim::Entity& Simulation::EntityOf(uint32_t id, const char* what) const {
  const sim::Entity* entity = state_.Find(id);
  if (!entity) {
    throw ConfigureError(proto::ERROR_CODE_UNKNOWN_ENTITY, std::string(what) + ": no entity has id " +
                                                               std::to_string(id) + "; the world holds " +
                                                               sim::EntityList(state_));
  }
  return *entity;
}

uint32_t Simulation::Spawn(const proto::Spawn& spawn) {
  sim::SpawnPose pose{{spawn.position().x(), spawn.position().y(), spawn.position().z()}, spawn.yaw_deg() * kDegrees};
  // CheckConfigure let only the table's kinds through (wire/entity_kinds_wire.h).
  const auto kind = static_cast<sim::EntityKind>(spawn.kind());
  if (spawn.snap_to_lane() && kind == sim::EntityKind::kCar) {
    if (!scene_->road_graph) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                           "Spawn.snap_to_lane needs a map scene; scene '" + scene_->name + "' has no lanes");
    }
    const map::LaneProjection nearest = scene_->road_graph->Nearest(pose.position.head<2>());
    pose.position.head<2>() = nearest.lane.position;
    pose.yaw = nearest.lane.heading;
  }
  return Checked([&] { return world_->Spawn(state_, kind, spawn.name(), pose); });
}

void Simulation::RemoveEntity(uint32_t id, Change& change) {
  const std::string name = EntityOf(id, "Remove").name;
  Checked([&] { world_->Remove(state_, id); });
  for (std::size_t i = 0; i < cameras_.size(); ++i) {
    if (cameras_[i].name.empty() || cameras_[i].mounted_on != name) continue;
    cameras_[i] = {};
    change.removed_cameras.push_back(static_cast<uint32_t>(i));
  }
}

void Simulation::SetRoute(const proto::SetRoute& route) {
  EntityOf(route.entity_id(), "SetRoute");
  if (route.has_keep_route()) {
    Checked([&] { world_->SetCruiseSpeed(state_, route.entity_id(), route.speed()); });
    return;
  }
  std::vector<Eigen::Vector2d> points;
  bool closed = false;
  if (route.has_waypoints()) {
    for (const proto::Vec2& p : route.waypoints().points()) points.emplace_back(p.x(), p.y());
    closed = route.waypoints().closed();
  } else {
    const map::Route* named = scene_->map ? scene_->map->FindRoute(route.route_name()) : nullptr;
    if (!named) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "SetRoute.route_name '" + route.route_name() +
                                                                   "': scene '" + scene_->name +
                                                                   "' has no such route; its routes: " + RouteNames());
    }
    points = Checked([&] { return scene_->road_graph->SampleRoute(*named, 1.0).points; });
    closed = named->closed;
  }
  Checked([&] { world_->SetRoute(state_, route.entity_id(), std::move(points), closed, route.speed()); });
}

void Simulation::CommandUav(const proto::CommandUav& command) {
  EntityOf(command.entity_id(), "CommandUav");
  sim::UavOrder order;
  switch (command.order_case()) {
    case proto::CommandUav::kFollow:
      order.mode = sim::UavOrder::Mode::kFollow;
      order.target = command.follow().target_id();
      EntityOf(order.target, "CommandUav.follow.target_id");
      if (command.follow().altitude() > 0) order.altitude = command.follow().altitude();
      if (command.follow().pitch_down_deg() > 0) order.pitch_down_deg = command.follow().pitch_down_deg();
      break;
    case proto::CommandUav::kHold: {
      const proto::Vec3& p = command.hold().position();
      order.mode = sim::UavOrder::Mode::kHold;
      order.position = {p.x(), p.y(), p.z()};
      order.yaw = command.hold().yaw_deg() * kDegrees;
      break;
    }
    case proto::CommandUav::kVelocity: {
      const proto::Vec3& v = command.velocity().velocity();
      order.mode = sim::UavOrder::Mode::kVelocity;
      order.velocity = {v.x(), v.y(), v.z()};
      order.yaw_rate = command.velocity().yaw_rate_deg() * kDegrees;
      break;
    }
    case proto::CommandUav::kTrack:
      order = TrackOrder(command);
      break;
    case proto::CommandUav::ORDER_NOT_SET:
      throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT,
                           "CommandUav needs an order: follow, hold, velocity or track");
  }
  Checked([&] { world_->SetUavOrder(state_, command.entity_id(), order); });
}

sim::UavOrder Simulation::TrackOrder(const proto::CommandUav& command) const {
  const proto::CommandUav::Track& track = command.track();
  const sim::Entity& uav = *state_.Find(command.entity_id());
  const int camera = FindCamera(track.camera());
  if (camera < 0 || cameras_[static_cast<std::size_t>(camera)].mounted_on != uav.name) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "CommandUav.track.camera '" + track.camera() +
                                                                 "' is not a camera mounted on '" + uav.name +
                                                                 "'; its cameras steer it: " + CamerasOn(uav.name));
  }
  const sim::CameraSpec& spec = cameras_[static_cast<std::size_t>(camera)];
  sim::UavOrder order;
  order.mode = sim::UavOrder::Mode::kTrack;
  order.track.fov_y = spec.fov_y_deg * kDegrees;
  order.track.pitch_down = spec.pitch_down_deg * kDegrees;
  order.track.distance = track.distance();
  order.track.altitude = track.altitude() > 0 ? track.altitude() : uav.body.position.z();
  order.yaw = uav.body.Yaw();
  return order;
}

std::string Simulation::CamerasOn(const std::string& entity) const {
  std::string names;
  for (const sim::CameraSpec& camera : cameras_) {
    if (camera.mounted_on != entity) continue;
    names += (names.empty() ? "'" : ", '") + camera.name + "'";
  }
  return names.empty() ? "none (add one with AddCamera)" : names;
}

void Simulation::AddCamera(const proto::AddCamera& camera) {
  if (FindCamera(camera.name()) >= 0) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT,
                         "AddCamera.name: a camera named '" + camera.name() + "' already exists");
  }
  if (!camera.mounted_on().empty() && !state_.FindByName(camera.mounted_on())) {
    throw ConfigureError(proto::ERROR_CODE_UNKNOWN_ENTITY, "AddCamera.mounted_on: no entity is named '" +
                                                               camera.mounted_on() + "'; the world holds " +
                                                               sim::EntityList(state_));
  }
  sim::CameraSpec spec;
  spec.name = camera.name();
  spec.mounted_on = camera.mounted_on();
  spec.width = camera.width();
  spec.height = camera.height();
  spec.fov_y_deg = static_cast<float>(camera.fov_y_deg());
  spec.pitch_down_deg = static_cast<float>(camera.pitch_down_deg());
  spec.yaw_deg = static_cast<float>(camera.yaw_deg());
  spec.gimbal = camera.gimbal();
  spec.offset = {camera.offset().x(), camera.offset().y(), camera.offset().z()};
  // A removed camera's index is never reused until the next LoadMap or
  // Reset, so a subscription by index can never be handed another camera.
  std::size_t live = 0;
  for (const auto& c : cameras_) live += c.name.empty() ? 0 : 1;
  if (live >= kMaxCameras || cameras_.size() >= kMaxCameraIndices) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_STATE,
                         "the world has " + std::to_string(live) + " cameras (at most " + std::to_string(kMaxCameras) +
                             ") and " + std::to_string(cameras_.size()) +
                             " camera indices used since the map was "
                             "loaded (at most " +
                             std::to_string(kMaxCameraIndices) + "); remove one, or Reset");
  }
  cameras_.push_back(std::move(spec));
  camera_added_ = true;
}

void Simulation::SetCameraPose(const proto::SetCameraPose& pose) {
  const int index = FindCamera(pose.camera());
  if (index < 0) {
    throw ConfigureError(proto::ERROR_CODE_UNKNOWN_CAMERA,
                         "SetCameraPose.camera: no camera is named '" + pose.camera() + "'");
  }
  sim::CameraSpec& camera = cameras_[static_cast<std::size_t>(index)];
  if (!camera.mounted_on.empty()) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "SetCameraPose moves cameras fixed in the world; '" +
                                                                 camera.name + "' is mounted on '" + camera.mounted_on +
                                                                 "' (add one without mounted_on)");
  }
  camera.offset = {pose.position().x(), pose.position().y(), pose.position().z()};
  camera.yaw_deg = static_cast<float>(pose.yaw_deg());
  camera.pitch_down_deg = static_cast<float>(pose.pitch_down_deg());
}

void Simulation::RemoveCamera(const std::string& name, Change& change) {
  const int index = FindCamera(name);
  if (index < 0) {
    throw ConfigureError(proto::ERROR_CODE_UNKNOWN_CAMERA, "RemoveCamera.name: no camera is named '" + name + "'");
  }
  if (static_cast<std::size_t>(index) < scene_->cameras.size()) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "RemoveCamera.name: camera '" + name +
                                                                 "' belongs to the scene; only cameras added "
                                                                 "with AddCamera can be removed");
  }
  cameras_[static_cast<std::size_t>(index)] = {};
  change.removed_cameras.push_back(static_cast<uint32_t>(index));
}

void Simulation::QueryRoad(const proto::QueryRoad& query, proto::RoadQueryResult& out) const {
  if (!scene_->road_graph) {
    throw ConfigureError(proto::ERROR_CODE_INVALID_STATE, "QueryRoad needs a map scene (--map or LoadMap); scene '" +
                                                              scene_->name + "' has no road graph");
  }
  const map::RoadGraph& graph = *scene_->road_graph;
  const Eigen::Vector2d point(query.point().x(), query.point().y());
  std::vector<map::SegmentId> route;
  if (!query.route().empty()) {
    const map::Route* named = scene_->map ? scene_->map->FindRoute(query.route()) : nullptr;
    if (!named) {
      throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, "QueryRoad.route '" + query.route() + "': scene '" +
                                                                   scene_->name + "' has no such route; its routes: " +
                                                                   RouteNames());
    }
    route = Checked([&] { return graph.RouteSegments(*named); });
  }
  const map::LaneProjection nearest =
      !route.empty()      ? graph.NearestOnRoute(point, route)
      : query.use_heading() ? graph.Nearest(point, query.heading_deg() * kDegrees)
                            : graph.Nearest(point);
  SetLanePoint(nearest.lane, *out.mutable_nearest());
  out.set_distance(nearest.distance);
  out.set_lateral_offset(nearest.lateral_offset);
  if (query.count() == 0) return;
  const int count = static_cast<int>(query.count());
  for (const map::LanePoint& ahead : route.empty() ? graph.PointsAhead(nearest.lane, query.step(), count)
                                                   : graph.PointsAlongRoute(nearest.lane, query.step(), count, route)) {
    SetLanePoint(ahead, *out.add_ahead());
  }
}

std::string Simulation::RouteNames() const {
  std::string names;
  if (scene_->map) {
    for (const auto& r : scene_->map->routes) names += (names.empty() ? "'" : ", '") + r.name + "'";
  }
  return names.empty() ? "none" : names;
}

// Checked by CheckConfigure (names and ranges) before it gets here.
void Simulation::SetConditions(const proto::SetConditions& request, Change& change) {
  RefuseWhileLogging("SetConditions", "a log holds one look");
  conditions::Conditions next = conditions_;
  if (!request.quality().empty()) next.quality = *conditions::FindQuality(request.quality());
  if (request.has_noise_read()) next.noise_read = request.noise_read();
  if (request.has_noise_shot()) next.noise_shot = request.noise_shot();
  randomize_seed_ = request.randomize_seed();
  randomize_every_ = request.randomize_every_frames();
  if (randomize_seed_ != 0) {
    conditions_ = next;
    DrawConditions();
    change.new_conditions = true;
    return;
  }
  if (!request.preset().empty()) {
    next.preset = *conditions::FindByName(request.preset());
    next.hour = conditions::Info(next.preset).hour;
  }
  if (request.has_hour()) next.hour = request.hour();
  conditions_ = next;
  change.new_conditions = true;
}

// Ranges are checked by CheckConfigure; whether the lens folds depends on
// the coefficients already in force too, so it is checked here.
void Simulation::SetEffects(const proto::CameraEffects& request, Change& change) {
  effects::CameraEffects next = effects_;
  wire::ApplyEffects(request, next);
  const std::string problem = effects::CheckLens(next);  // each field's range was checked on arrival
  if (!problem.empty()) throw ConfigureError(proto::ERROR_CODE_INVALID_ARGUMENT, problem);
  effects_ = next;
  change.new_effects = true;
}

void Simulation::FillWorldInfo(proto::WorldInfo& out) const {
  out.Clear();
  out.set_scene_name(scene_->name);
  out.set_frame_id(state_.frame_id);
  out.set_log_file(log_file_);
  for (const sim::Entity& entity : state_.entities) {
    proto::EntityInfo* info = out.add_entities();
    info->set_id(entity.id);
    info->set_name(entity.name);
    info->set_kind(static_cast<proto::EntityKind>(entity.kind));
  }
  for (const sim::CameraSpec& camera : cameras_) {
    proto::CameraInfo* info = out.add_cameras();
    if (camera.name.empty()) continue;  // removed: an empty entry keeps the indices of the rest
    info->set_name(camera.name);
    info->set_width(camera.width);
    info->set_height(camera.height);
    info->set_fov_y_deg(camera.fov_y_deg);
    info->set_mounted_on(camera.mounted_on);
  }
  if (scene_->map) {
    for (const auto& route : scene_->map->routes) out.add_routes(route.name);
  }
  proto::ConditionsInfo& look = *out.mutable_conditions();
  look.set_preset(std::string(conditions::Info(conditions_.preset).name));
  look.set_hour(conditions_.hour);
  look.set_quality(std::string(conditions::QualityName(conditions_.quality)));
  look.set_exposure(conditions_.exposure);
  look.set_variation(conditions_.variation);
  look.set_randomize_seed(randomize_seed_);
  look.set_randomize_every_frames(randomize_every_);
  look.set_noise_read(conditions_.noise_read);
  look.set_noise_shot(conditions_.noise_shot);
  wire::FillEffects(effects_, *out.mutable_effects());
}

}  // namespace sim4cv::daemon
