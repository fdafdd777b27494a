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
  Entry entry{instance, object_class, Source::kStatic, {}, 0.5 * (high - low)};
  // The mesh's origin need not be its box's centre (map objects stand on theirs).
  entry.pose.position = world_from_model_d.topLeftCorner<3, 3>() * (0.5 * (low + high)) +
                        world_from_model_d.block<3, 1>(0, 3);
  entry.pose.orientation = Eigen::Quaterniond(Eigen::Matrix3d(world_from_model_d.topLeftCorner<3, 3>())).normalized();
  Insert(entry);
}

void ObjectCatalog::AddBody(InstanceId instance, uint32_t object_class, Source source,
                            const Eigen::Vector3d& half_extents) {
  SIM4CV_THROW_UNLESS(source != Source::kStatic, "AddBody needs a moving body; use AddStatic");
  Insert({instance, object_class, source, {}, half_extents});
}

void ObjectCatalog::Insert(const Entry& entry) {
  const auto at = std::lower_bound(entries_.begin(), entries_.end(), entry.instance,
                                   [](const Entry& e, InstanceId id) { return e.instance < id; });
  SIM4CV_THROW_UNLESS(at == entries_.end() || at->instance != entry.instance,
                      "instance id " << entry.instance << " is labelled twice");
  entries_.insert(at, entry);
}

void ObjectCatalog::Fill(const sim::State& state, const BoxProjector& camera, std::span<const GroundTruthBox> visible,
                         std::vector<ObjectGroundTruth>& out) const {
  out.clear();
  auto next_visible = visible.begin();
  for (const Entry& entry : entries_) {
    // Both lists are ordered by instance id: one merged walk.
    while (next_visible != visible.end() && next_visible->instance < entry.instance) ++next_visible;
    const bool has_visible_box = next_visible != visible.end() && next_visible->instance == entry.instance;
    ObjectGroundTruth object;
    object.instance = entry.instance;
    object.object_class = entry.object_class;
    object.half_extents = entry.half_extents;
    object.has_visible_box = has_visible_box;
    if (entry.source == Source::kStatic) {
      object.position = entry.pose.position;
      object.orientation = entry.pose.orientation;
    } else {
      const sim::BodyState& body = entry.source == Source::kCar ? state.car : state.uav;
      object.position = body.position;
      object.orientation = body.orientation.normalized();
      object.linear_velocity = body.linear_velocity;
      object.angular_velocity = body.angular_velocity;
    }
    object.projected_box = camera.Project(object.position, object.orientation, object.half_extents);
    if (has_visible_box || !object.projected_box.empty()) out.push_back(object);
  }
}

}  // namespace sim4cv::render
