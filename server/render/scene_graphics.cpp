#include "server/render/scene_graphics.h"

#include <cmath>
#include <numbers>

#include "sim4cv.pb.h"
#include "server/render/camera_math.h"
#include "server/render/map_meshes.h"
#include "server/render/mesh_builder.h"
#include "server/sim/vehicles/gimbal.h"

namespace sim4cv::render {
namespace {

Eigen::Matrix4f BodyPose(const sim::BodyState& body) {
  return PoseMatrix(body.position.cast<float>(), body.orientation.cast<float>());
}

// A stable, pleasant colour per building so frames are easy to read.
Eigen::Vector3f BuildingColour(std::size_t index) {
  static const Eigen::Vector3f palette[] = {{0.62f, 0.55f, 0.48f}, {0.50f, 0.52f, 0.58f}, {0.70f, 0.64f, 0.52f},
                                            {0.45f, 0.40f, 0.38f}, {0.58f, 0.60f, 0.55f}};
  return palette[index % std::size(palette)];
}

}  // namespace

SceneGraphics::SceneGraphics(const sim::Scene& scene) : scene_(scene) {
  auto add_static = [&](Mesh mesh, InstanceId instance, uint32_t object_class, const Eigen::Matrix4f& pose) {
    if (instance != kUnlabelled) {
      labelled_.push_back({instance, object_class, 0});
      catalog_.AddStatic(instance, object_class, mesh, pose);
    }
    meshes_.push_back(std::move(mesh));
    items_.push_back({static_cast<MeshId>(meshes_.size() - 1), pose, instance});
  };
  if (scene.map) {
    // Tile maps bring their own ground, roads and labelled dressing.
    for (auto& drawable : BuildMapDrawables(*scene.map, *scene.road_graph, static_cast<InstanceId>(sim::kFirstBuildingId))) {
      add_static(std::move(drawable.mesh), drawable.instance, drawable.object_class, drawable.world_from_model);
    }
  } else {
    add_static(MakeGroundPlane(scene.ground_half_size, {0.55f, 0.50f, 0.40f}), kUnlabelled, 0,
               Eigen::Matrix4f::Identity());
    add_static(MakeRoadLoop(scene.road_loop, scene.lane_width, {0.22f, 0.22f, 0.24f}, {0.95f, 0.95f, 0.92f}), kUnlabelled,
               0, Eigen::Matrix4f::Identity());
  }
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const auto& b = scene.buildings[i];
    const Eigen::Vector3f half(b.half_size.x(), b.half_size.y(), b.height / 2.0f);
    const Eigen::Quaternionf yaw(Eigen::AngleAxisf(b.yaw_deg * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitZ()));
    add_static(MakeBox(half, BuildingColour(i)), static_cast<InstanceId>(b.id), proto::OBJECT_CLASS_BUILDING,
               PoseMatrix(Eigen::Vector3f(b.centre.x(), b.centre.y(), half.z()), yaw));
  }
  static_item_count_ = items_.size();
  const Eigen::Vector3f car_size = 2.0f * scene.car.params.chassis_half_extents.cast<float>();
  meshes_.push_back(MakeCarMesh(car_size.x(), car_size.y(), car_size.z(), {0.80f, 0.10f, 0.10f}));
  car_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  meshes_.push_back(MakeUavMesh(2.0f * static_cast<float>(scene.uav.params.half_extents.x()), {0.15f, 0.15f, 0.18f}));
  uav_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  labelled_.insert(labelled_.begin(), {{static_cast<InstanceId>(sim::kCarEntityId), proto::OBJECT_CLASS_CAR, 0},
                                       {static_cast<InstanceId>(sim::kUavEntityId), proto::OBJECT_CLASS_UAV, 0}});
  // The physics boxes, which the car's and the UAV's meshes fit inside.
  catalog_.AddBody(static_cast<InstanceId>(sim::kCarEntityId), proto::OBJECT_CLASS_CAR, ObjectCatalog::Source::kCar,
                   scene.car.params.chassis_half_extents);
  catalog_.AddBody(static_cast<InstanceId>(sim::kUavEntityId), proto::OBJECT_CLASS_UAV, ObjectCatalog::Source::kUav,
                   scene.uav.params.half_extents);
  for (const auto& object : labelled_) instance_id_bound_ = std::max<std::size_t>(instance_id_bound_, object.instance + 1u);
  items_.resize(static_item_count_ + 2);
}

const std::vector<DrawItem>& SceneGraphics::DrawItems(const sim::State& state) {
  items_[static_item_count_] = {car_mesh_, BodyPose(state.car), static_cast<InstanceId>(sim::kCarEntityId)};
  items_[static_item_count_ + 1] = {uav_mesh_, BodyPose(state.uav), static_cast<InstanceId>(sim::kUavEntityId)};
  return items_;
}

CameraView SceneGraphics::CameraAt(std::size_t camera_index, const sim::State& state) const {
  const sim::CameraSpec& spec = scene_.cameras.at(camera_index);
  const sim::BodyState& mount = scene_.MountedOnCar(spec) ? state.car : state.uav;
  const vehicles::Pose body{mount.position, mount.orientation};
  vehicles::Pose camera;
  if (spec.gimbal) {
    camera = vehicles::GimbalCameraPose(body, {spec.pitch_down_deg, spec.offset});
  } else {
    const double pitch = spec.pitch_down_deg * std::numbers::pi / 180.0;
    camera.position = body.position + body.orientation * spec.offset;
    camera.orientation = body.orientation * Eigen::Quaterniond(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()));
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
