#include "server/render/object_catalog.h"

#include <algorithm>
#include <limits>

#include "server/common/check.h"

namespace sim4cv::render {

void ObjectCatalog::AddStatic(InstanceId instance, uint32_t object_class, const Mesh& model,
                              const Eigen::Matrix4f& world_from_model) {
  SIM4CV_THROW_UNLESS(!model.vertices.empty(), "labelled object " << instance << " has an empty mesh");
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d high = -low;
  for (const Vertex& vertex : model.vertices) {
    const Eigen::Vector3d p(vertex.position[0], vertex.position[1], vertex.position[2]);
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const Eigen::Matrix4d world_from_model_d = world_from_model.cast<double>();
  MovingObject entry;
  entry.instance = instance;
  entry.object_class = object_class;
  entry.half_extents = 0.5 * (high - low);
  // The mesh's origin need not be its box's centre (map objects stand on theirs).
  entry.position = world_from_model_d.topLeftCorner<3, 3>() * (0.5 * (low + high)) +
                   world_from_model_d.block<3, 1>(0, 3);
  entry.orientation = Eigen::Quaterniond(Eigen::Matrix3d(world_from_model_d.topLeftCorner<3, 3>())).normalized();
  Insert(entry);
}

void ObjectCatalog::Insert(const MovingObject& entry) {
  const auto at = std::lower_bound(entries_.begin(), entries_.end(), entry.instance,
                                   [](const MovingObject& e, InstanceId id) { return e.instance < id; });
  SIM4CV_THROW_UNLESS(at == entries_.end() || at->instance != entry.instance,
                      "instance id " << entry.instance << " is labelled twice");
  entries_.insert(at, entry);
}

void ObjectCatalog::Fill(std::span<const MovingObject> moving, const BoxProjector& camera,
                         std::span<const GroundTruthBox> visible, std::vector<ObjectGroundTruth>& out) const {
  out.clear();
  auto next_visible = visible.begin();
  auto next_static = entries_.begin();
  auto next_moving = moving.begin();
  // All three lists are ordered by instance id: one merged walk.
  while (next_static != entries_.end() || next_moving != moving.end()) {
    const bool take_static =
        next_moving == moving.end() || (next_static != entries_.end() && next_static->instance < next_moving->instance);
    const MovingObject& entry = take_static ? *next_static++ : *next_moving++;
    SIM4CV_ASSERT(take_static || next_static == entries_.end() || next_static->instance != entry.instance);
    while (next_visible != visible.end() && next_visible->instance < entry.instance) ++next_visible;
    ObjectGroundTruth object;
    object.instance = entry.instance;
    object.object_class = entry.object_class;
    object.position = entry.position;
    object.orientation = entry.orientation.normalized();
    object.linear_velocity = entry.linear_velocity;
    object.angular_velocity = entry.angular_velocity;
    object.half_extents = entry.half_extents;
    object.has_visible_box = next_visible != visible.end() && next_visible->instance == entry.instance;
    object.projected_box = camera.Project(object.position, object.orientation, object.half_extents);
    if (object.has_visible_box || !object.projected_box.empty()) out.push_back(object);
  }
}

}  // namespace sim4cv::render
