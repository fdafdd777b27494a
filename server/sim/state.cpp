#include "server/sim/state.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sim4cv::sim {

const Entity* State::Find(uint32_t id) const {
  const auto at =
      std::lower_bound(entities.begin(), entities.end(), id, [](const Entity& a, uint32_t wanted) { return a.id < wanted; });
  return at != entities.end() && at->id == id ? &*at : nullptr;
}

Entity* State::Find(uint32_t id) { return const_cast<Entity*>(std::as_const(*this).Find(id)); }

const Entity* State::FindByName(const std::string& name) const {
  for (const Entity& entity : entities) {
    if (entity.name == name) return &entity;
  }
  return nullptr;
}

double BodyState::Yaw() const {
  const Eigen::Vector3d forward = orientation * Eigen::Vector3d::UnitX();
  return std::atan2(forward.y(), forward.x());
}

}  // namespace sim4cv::sim
