#include "server/render/scene_graphics.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "protocol/semantic_classes.h"
#include "server/common/check.h"
#include "server/render/camera_math.h"
#include "server/render/map_meshes.h"
#include "server/render/mesh_builder.h"
#include "server/render/object_meshes.h"
#include "server/render/traffic_meshes.h"
#include "server/sim/entity_kind_registry.h"
#include "server/wire/entity_kinds_wire.h"
#include "server/sim/vehicles/gimbal.h"
#include "sim4cv.pb.h"

namespace sim4cv::render {
namespace {

Eigen::Matrix4f BodyPose(const sim::BodyState& body) {
  return PoseMatrix(body.position.cast<float>(), body.orientation.cast<float>());
}

// A stable, pleasant colour per building so frames are easy to read.
Eigen::Vector3f BuildingColour(std::size_t index) {
  static const Eigen::Vector3f palette[] = {{0.62f, 0.55f, 0.48f},
                                            {0.50f, 0.52f, 0.58f},
                                            {0.70f, 0.64f, 0.52f},
                                            {0.45f, 0.40f, 0.38f},
                                            {0.58f, 0.60f, 0.55f}};
  return palette[index % std::size(palette)];
}

}  // namespace

SceneGraphics::SceneGraphics(const sim::Scene& scene) : scene_(scene) {
  auto add_static = [&](Mesh mesh, InstanceId instance, uint32_t object_class, const Eigen::Matrix4f& pose) {
    if (instance != kUnlabelled) {
      static_labelled_.push_back({instance, object_class, 0});
      catalog_.AddStatic(instance, object_class, mesh, pose);
    }
    meshes_.push_back(std::move(mesh));
    items_.push_back({static_cast<MeshId>(meshes_.size() - 1), pose, instance});
  };
  if (scene.map) {
    // Tile maps bring their own ground, roads and labelled dressing.
    for (auto& drawable :
         BuildMapDrawables(*scene.map, *scene.road_graph, static_cast<InstanceId>(sim::kFirstBuildingId))) {
      if (drawable.object_class == proto::OBJECT_CLASS_LANTERN) {
        lamps_.push_back((drawable.world_from_model * LanternLightOffset().homogeneous()).head<3>());
      }
      add_static(std::move(drawable.mesh), drawable.instance, drawable.object_class, drawable.world_from_model);
    }
  } else {
    add_static(MakeGroundPlane(scene.ground_half_size, {0.55f, 0.50f, 0.40f}), kUnlabelled, 0,
               Eigen::Matrix4f::Identity());
    add_static(MakeRoadLoop(scene.road_loop, scene.lane_width, {0.22f, 0.22f, 0.24f}, {0.95f, 0.95f, 0.92f}),
               kUnlabelled, 0, Eigen::Matrix4f::Identity());
  }
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const auto& b = scene.buildings[i];
    const Eigen::Vector3f half(b.half_size.x(), b.half_size.y(), b.height / 2.0f);
    const Eigen::Quaternionf yaw(
        Eigen::AngleAxisf(b.yaw_deg * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitZ()));
    add_static(Labelled(MakeBox(half, BuildingColour(i)), SemanticClass::kBuilding), static_cast<InstanceId>(b.id),
               proto::OBJECT_CLASS_BUILDING,
               PoseMatrix(Eigen::Vector3f(b.centre.x(), b.centre.y(), half.z()), yaw));
  }
  const auto add_mesh = [&](Mesh mesh) {
    meshes_.push_back(std::move(mesh));
    return static_cast<MeshId>(meshes_.size() - 1);
  };
  // One set of walker meshes for the spawned pedestrians and the traffic's walkers.
  walker_looks_ = std::make_unique<WalkerLooks>(add_mesh);
  if (scene.traffic) {
    const traffic::TrafficIds ids = sim::TrafficIdsOf(scene);
    for (const auto& object : static_labelled_) SIM4CV_DEMAND(object.instance < ids.parked);
    const auto add_item = [&](MeshId mesh, InstanceId instance, uint32_t object_class, const Eigen::Matrix4f& pose) {
      if (instance != kUnlabelled) {
        static_labelled_.push_back({instance, object_class, 0});
        catalog_.AddStatic(instance, object_class, meshes_[mesh], pose);
      }
      items_.push_back({mesh, pose, instance});
    };
    traffic_ =
        std::make_unique<TrafficGraphics>(*scene.traffic, ids, scene.car.params.chassis_half_extents,
                                          vehicles::BoxCentreHeightAtRest(scene.car.params), *walker_looks_,
                                          add_mesh, add_item);
  }
  static_item_count_ = items_.size();
  for (DrawItem& item : items_) {
    item.previous_world_from_model = item.world_from_model;  // they never move
    item.fixed = true;
  }
  const Eigen::Vector3f car_size = 2.0f * scene.car.params.chassis_half_extents.cast<float>();
  // The scene's target car is red, as in the paper; other cars are blue.
  meshes_.push_back(MakeCarMesh(car_size.x(), car_size.y(), car_size.z(), {0.80f, 0.10f, 0.10f}));
  target_car_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  meshes_.push_back(MakeCarMesh(car_size.x(), car_size.y(), car_size.z(), {0.15f, 0.30f, 0.75f}));
  car_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  uav_span_ = 2.0f * static_cast<float>(scene.uav.params.half_extents.x());
  UavParts uav = MakeUavParts(uav_span_, {0.15f, 0.15f, 0.18f});
  uav_mesh_ = add_mesh(std::move(uav.body));
  rotor_mesh_ = add_mesh(std::move(uav.rotor));
  for (const sim::EntityKindEntry& kind : sim::RegisteredKinds()) {
    const Eigen::Vector3f colour(kind.colour[0], kind.colour[1], kind.colour[2]);
    registered_meshes_.push_back({kind.info.kind, add_mesh(MakeBox(kind.half_extents.cast<float>(), colour))});
  }
  // Entities take the ids below the static objects' (sim::kMaxEntityId).
  instance_id_bound_ = sim::kMaxEntityId + 1;
  for (const auto& object : static_labelled_)
    instance_id_bound_ = std::max<std::size_t>(instance_id_bound_, object.instance + 1u);
  if (traffic_) instance_id_bound_ = std::max<std::size_t>(instance_id_bound_, traffic_->id_bound());
}

void SceneGraphics::Update(const sim::State& state) {
  previous_items_.assign(items_.begin(), items_.end());  // keeps its capacity
  items_.resize(static_item_count_);
  labelled_.clear();
  moving_.clear();
  for (const sim::Entity& entity : state.entities) {
    const auto instance = static_cast<InstanceId>(entity.id);
    // The 3D box: the physics box, which the car's and the UAV's meshes fit
    // inside; a pedestrian's body stands on its feet, its box half its height up.
    Eigen::Vector3d box_centre = entity.body.position, half_extents;
    MeshId mesh = 0;
    const uint32_t object_class = wire::ObjectClassOf(entity.kind);
    switch (entity.kind) {
      case sim::EntityKind::kCar:
        mesh = entity.id == sim::kCarEntityId ? target_car_mesh_ : car_mesh_;
        half_extents = scene_.car.params.chassis_half_extents;
        break;
      case sim::EntityKind::kUav:
        mesh = uav_mesh_;
        half_extents = scene_.uav.params.half_extents;
        break;
      case sim::EntityKind::kPedestrian:
        half_extents = kPedestrianBox;
        box_centre.z() += kPedestrianBox.z();
        break;
      default:  // a registered kind (sim/entity_kind_registry.h): a box of its colour
        for (const auto& [kind, box] : registered_meshes_) mesh = kind == entity.kind ? box : mesh;
        half_extents = sim::FindRegisteredKind(entity.kind)->half_extents;
        break;
    }
    const Eigen::Matrix4f pose = BodyPose(entity.body);
    if (entity.kind == sim::EntityKind::kPedestrian) {
      walker_looks_->Append(items_, instance, pose, entity.body.position.head<2>(), entity.body.Yaw(),
                            entity.body.linear_velocity.norm());
    } else {
      items_.push_back({mesh, pose, instance});
    }
    // Moving parts: a UAV's rotors (same instance).
    if (entity.kind == sim::EntityKind::kUav) {
      for (std::size_t rotor = 0; rotor < 4; ++rotor) {
        items_.push_back({rotor_mesh_, pose * RotorPose(uav_span_, rotor, state.sim_time), instance});
      }
    }
    labelled_.push_back({instance, object_class, 0});
    moving_.push_back({instance, object_class, box_centre, entity.body.orientation, entity.body.linear_velocity,
                       entity.body.angular_velocity, half_extents});
  }
  labelled_.insert(labelled_.end(), static_labelled_.begin(), static_labelled_.end());
  if (traffic_) traffic_->Append(state.traffic, state.sim_time, items_, labelled_, moving_);
  // A car's lamps sit at the front of its box, at two thirds of its height,
  // and shine a little down the road.
  headlights_.clear();
  for (const MovingObject& object : moving_) {
    if (object.object_class != static_cast<uint32_t>(proto::OBJECT_CLASS_CAR)) continue;
    const Eigen::Vector3d front = object.position + object.orientation * Eigen::Vector3d(object.half_extents.x(), 0.0,
                                                                                         0.3 * object.half_extents.z());
    const Eigen::Vector3d ahead = object.orientation * Eigen::Vector3d(1.0, 0.0, -0.025);
    headlights_.push_back({front.cast<float>(), ahead.normalized().cast<float>()});
  }
  LinkPreviousTransforms();
  // Room for the next Update's copy now, so a warm Update never allocates.
  previous_items_.reserve(items_.capacity());
  headlights_.reserve(moving_.capacity());
}

// Items are rebuilt in the same order every frame (entities in State order,
// then traffic), so an item is matched with the one at its index a frame ago
// if that drew the same mesh for the same instance; anything else (a new
// entity, a reordering after a removal) gets no motion of its own.
void SceneGraphics::LinkPreviousTransforms() {
  for (std::size_t i = static_item_count_; i < items_.size(); ++i) {
    DrawItem& item = items_[i];
    const bool same = i < previous_items_.size() && previous_items_[i].mesh == item.mesh &&
                      previous_items_[i].instance == item.instance;
    item.previous_world_from_model = same ? previous_items_[i].world_from_model : item.world_from_model;
  }
}

CameraView SceneGraphics::CameraAt(const sim::CameraSpec& spec, const sim::State& state) const {
  const sim::Entity* mount = spec.mounted_on.empty() ? nullptr : state.FindByName(spec.mounted_on);
  const vehicles::Pose body = mount ? vehicles::Pose{mount->body.position, mount->body.orientation} : vehicles::Pose{};
  vehicles::Pose camera;
  if (spec.gimbal) {
    camera = vehicles::GimbalCameraPose(body, {spec.pitch_down_deg, spec.offset});
  } else {
    const double pitch = spec.pitch_down_deg * std::numbers::pi / 180.0;
    const double yaw = spec.yaw_deg * std::numbers::pi / 180.0;
    camera.position = body.position + body.orientation * spec.offset;
    camera.orientation = body.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) *
                         Eigen::Quaterniond(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()));
  }
  // Camera frame: x is the viewing direction and z the image's up; the
  // up vector stays well defined even when looking straight down.
  const Eigen::Vector3d eye = camera.position;
  const Eigen::Vector3d look = camera.orientation * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d up = camera.orientation * Eigen::Vector3d::UnitZ();
  CameraView view;
  view.world_from_camera = LookAt(eye.cast<float>(), (eye + look).cast<float>(), up.cast<float>());
  view.fov_y_deg = spec.fov_y_deg;
  view.near_m = 0.1f;
  view.far_m = 1000.0f;
  view.width = spec.width;
  view.height = spec.height;
  return view;
}

}  // namespace sim4cv::render
