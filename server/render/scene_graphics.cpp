#include "server/render/scene_graphics.h"

#include <cmath>
#include <numbers>

#include "sim4cv.pb.h"
#include "server/render/camera_math.h"
#include "server/render/mesh_builder.h"

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
  auto add_static = [&](Mesh mesh, InstanceId instance, const Eigen::Matrix4f& pose) {
    meshes_.push_back(std::move(mesh));
    items_.push_back({static_cast<MeshId>(meshes_.size() - 1), pose, instance});
  };
  add_static(MakeGroundPlane(scene.ground_half_size, {0.55f, 0.50f, 0.40f}), kUnlabelled, Eigen::Matrix4f::Identity());
  add_static(MakeRoadLoop(scene.road_loop, scene.lane_width, {0.22f, 0.22f, 0.24f}, {0.95f, 0.95f, 0.92f}), kUnlabelled,
             Eigen::Matrix4f::Identity());
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const auto& b = scene.buildings[i];
    const Eigen::Vector3f half(b.half_size.x(), b.half_size.y(), b.height / 2.0f);
    const Eigen::Quaternionf yaw(Eigen::AngleAxisf(b.yaw_deg * std::numbers::pi_v<float> / 180.0f, Eigen::Vector3f::UnitZ()));
    add_static(MakeBox(half, BuildingColour(i)), static_cast<InstanceId>(b.id),
               PoseMatrix(Eigen::Vector3f(b.centre.x(), b.centre.y(), half.z()), yaw));
    labelled_.push_back({static_cast<InstanceId>(b.id), proto::OBJECT_CLASS_BUILDING, 0});
  }
  static_item_count_ = items_.size();
  meshes_.push_back(MakeCarMesh(scene.car.length, scene.car.width, scene.car.height, {0.80f, 0.10f, 0.10f}));
  car_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  meshes_.push_back(MakeUavMesh(scene.uav.span, {0.15f, 0.15f, 0.18f}));
  uav_mesh_ = static_cast<MeshId>(meshes_.size() - 1);
  labelled_.insert(labelled_.begin(), {{static_cast<InstanceId>(sim::kCarEntityId), proto::OBJECT_CLASS_CAR, 0},
                                       {static_cast<InstanceId>(sim::kUavEntityId), proto::OBJECT_CLASS_UAV, 0}});
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
  // The gimbal holds the pitch whatever the body does; only the body's yaw
  // turns the camera. The camera hangs just below the body so it never sees it.
  const sim::BodyState& mount = state.uav;
  const double yaw = mount.Yaw();
  const double pitch = spec.pitch_down_deg * std::numbers::pi / 180.0;
  const Eigen::Vector3d eye = mount.position - Eigen::Vector3d(0, 0, 0.3);
  const Eigen::Vector3d look(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), -std::sin(pitch));
  // The camera's own up vector: well defined even when looking straight down.
  const Eigen::Vector3d up(std::cos(yaw) * std::sin(pitch), std::sin(yaw) * std::sin(pitch), std::cos(pitch));
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
