#include "server/render/walker_looks.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "server/common/diagnostics.h"
#include "server/render/people_bundle.h"

namespace sim4cv::render {

Eigen::Matrix4f SwayPose(double phase, double speed) {
  const double walking = std::clamp(speed / 1.4, 0.0, 1.0);
  // GaitPhase makes one cycle per two steps: the body rolls once each way.
  const auto roll = static_cast<float>(kMaxSway * walking * std::sin(phase));
  const auto lean = static_cast<float>(kMaxSway * walking);
  Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
  pose.topLeftCorner<3, 3>() = (Eigen::AngleAxisf(lean, Eigen::Vector3f::UnitY()) *
                                Eigen::AngleAxisf(roll, Eigen::Vector3f::UnitX()))
                                   .toRotationMatrix();
  return pose;
}

WalkerLooks::WalkerLooks(const AddMesh& add_mesh, const std::vector<Person>& people) {
  for (const Person& person : people) {
    const MeshId full = add_mesh(person.full);
    people_.push_back({full, add_mesh(person.far)});
  }
  if (!people_.empty()) return;
  // Once per scene built: a build without the package should not go unnoticed.
  LOG_WARNING("no packaged people (built without sweethome3d-furniture, docs/assets.md): walkers are procedural "
              "box figures");
  for (uint32_t i = 0; i < kProceduralLooks; ++i) {
    PedestrianParts parts = MakePedestrianParts(i);
    procedural_.push_back({add_mesh(std::move(parts.body)), add_mesh(std::move(parts.leg)),
                           add_mesh(std::move(parts.arm))});
  }
}

void WalkerLooks::Append(std::vector<DrawItem>& items, InstanceId id, const Eigen::Matrix4f& ground_pose,
                         const Eigen::Vector2d& position, double heading, double speed) const {
  const double phase = GaitPhase(position, heading);
  if (packaged()) {
    const PersonIds& person = people_[id % people_.size()];
    DrawItem item{person.full, ground_pose * SwayPose(phase, speed), id};
    item.far_mesh = person.far;
    item.far_below_px = kFarPersonBelowPx;
    items.push_back(item);
    return;
  }
  const WalkerMeshIds& look = procedural_[id % procedural_.size()];
  items.push_back({look.body, ground_pose, id});
  AppendLimbs(items, look, ground_pose, position, heading, speed, id);
}

}  // namespace sim4cv::render
