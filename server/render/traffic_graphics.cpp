#include "server/render/traffic_graphics.h"

#include "server/common/check.h"
#include "server/render/camera_math.h"
#include "server/render/mesh_builder.h"
#include "server/render/traffic_meshes.h"
#include "sim4cv.pb.h"

namespace sim4cv::render {
namespace {

Eigen::Quaternionf Heading(double heading) {
  return Eigen::Quaternionf(Eigen::AngleAxisf(static_cast<float>(heading), Eigen::Vector3f::UnitZ()));
}

Eigen::Matrix4f GroundPose(const Eigen::Vector2d& position, double heading, double z) {
  return PoseMatrix(
      Eigen::Vector3f(static_cast<float>(position.x()), static_cast<float>(position.y()), static_cast<float>(z)),
      Heading(heading));
}

}  // namespace

TrafficGraphics::TrafficGraphics(const traffic::TrafficPlan& plan, const traffic::TrafficIds& ids,
                                 const Eigen::Vector3d& car_half_extents, double car_centre_height,
                                 const WalkerLooks& walker_looks, const AddMesh& add_mesh,
                                 const AddStatic& add_static)
    : plan_(plan),
      car_half_extents_(car_half_extents),
      car_centre_height_(car_centre_height),
      walker_looks_(walker_looks) {
  const Eigen::Vector3f car_size = 2.0f * car_half_extents.cast<float>();
  for (int i = 0; i < kCarVariants; ++i) {
    car_meshes_[i] = add_mesh(MakeCarMesh(car_size.x(), car_size.y(), car_size.z(), TrafficCarColour(i),
                                          static_cast<CarStyle>(i % kCarStyleCount)));
  }
  for (const traffic::Signal signal : {traffic::Signal::kGreen, traffic::Signal::kYellow, traffic::Signal::kRed}) {
    lamp_meshes_[static_cast<std::size_t>(signal)] = add_mesh(MakeLampMesh(signal));
  }
  if (!plan.crosswalks().empty()) {
    add_static(add_mesh(MakeCrosswalkMarkings(plan.crosswalks())), kUnlabelled, 0, Eigen::Matrix4f::Identity());
  }
  auto id = static_cast<InstanceId>(ids.parked);
  for (std::size_t i = 0; i < plan.parked_cars().size(); ++i) {
    const traffic::Pose2& parked = plan.parked_cars()[i];
    add_static(car_meshes_[i % kCarVariants], id++, proto::OBJECT_CLASS_CAR,
               GroundPose(parked.position, parked.heading, car_centre_height));
  }
  if (!plan.lights().empty()) {
    const MeshId light_mesh = add_mesh(MakeTrafficLightMesh());
    for (const traffic::TrafficPlan::Light& light : plan.lights()) {
      light_poses_.push_back(GroundPose(light.position, light.heading, 0.0));
      light_ids_.push_back(id);
      add_static(light_mesh, id++, proto::OBJECT_CLASS_TRAFFIC_LIGHT, light_poses_.back());
    }
  }
  SIM4CV_DEMAND(id == ids.cars);
  first_moving_car_ = static_cast<InstanceId>(ids.cars);
  first_walker_ = static_cast<InstanceId>(ids.walkers);
  id_bound_ = static_cast<InstanceId>(ids.end);
}

void TrafficGraphics::Append(const traffic::TrafficState& state, double sim_time, std::vector<DrawItem>& items,
                             std::vector<LabelledObject>& labelled, std::vector<MovingObject>& moving) const {
  // A lit lamp belongs to its light: its pixels count as the light's.
  for (std::size_t i = 0; i < light_poses_.size(); ++i) {
    const traffic::Signal signal = plan_.SignalAt(i, sim_time);
    Eigen::Matrix4f lamp = light_poses_[i];
    lamp.block<3, 1>(0, 3) += lamp.topLeftCorner<3, 3>() * LampOffset(signal);
    items.push_back({lamp_meshes_[static_cast<std::size_t>(signal)], lamp, light_ids_[i]});
  }
  // Labels a moving object whose 3D box is centred `box_z` above `ground`.
  const auto label = [&](InstanceId id, uint32_t object_class, const Eigen::Vector3d& ground, double heading,
                         double box_z, const Eigen::Vector3d& half_extents, const Eigen::Vector3d& velocity,
                         double yaw_rate) {
    labelled.push_back({id, object_class, 0});
    moving.push_back({id, object_class, ground + Eigen::Vector3d(0, 0, box_z),
                      Eigen::Quaterniond(Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ())), velocity,
                      Eigen::Vector3d(0, 0, yaw_rate), half_extents});
  };
  for (std::size_t i = 0; i < state.cars.size(); ++i) {
    const traffic::MovingCar& car = state.cars[i];
    const auto id = static_cast<InstanceId>(first_moving_car_ + i);
    items.push_back({car_meshes_[(i + plan_.parked_cars().size()) % kCarVariants],
                     GroundPose(car.position.head<2>(), car.heading, car_centre_height_), id});
    label(id, proto::OBJECT_CLASS_CAR, car.position, car.heading, car_centre_height_, car_half_extents_,
          car.linear_velocity, car.yaw_rate);
  }
  for (std::size_t i = 0; i < state.walkers.size(); ++i) {
    const traffic::Walker& walker = state.walkers[i];
    // The walker stands on its origin; its box is centred half its height up.
    const auto id = static_cast<InstanceId>(first_walker_ + i);
    walker_looks_.Append(items, id, GroundPose(walker.position.head<2>(), walker.heading, 0.0),
                         walker.position.head<2>(), walker.heading, walker.linear_velocity.norm());
    label(id, proto::OBJECT_CLASS_PEDESTRIAN, walker.position, walker.heading, kPedestrianBox.z(), kPedestrianBox,
          walker.linear_velocity, 0.0);
  }
}

}  // namespace sim4cv::render
