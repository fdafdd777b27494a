#include "server/sim/state.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sim4cv::sim {

const Agent* State::Find(uint32_t id) const {
  const auto at =
      std::lower_bound(agents.begin(), agents.end(), id, [](const Agent& a, uint32_t wanted) { return a.id < wanted; });
  return at != agents.end() && at->id == id ? &*at : nullptr;
}

Agent* State::Find(uint32_t id) { return const_cast<Agent*>(std::as_const(*this).Find(id)); }

const Agent* State::FindByName(const std::string& name) const {
  for (const Agent& agent : agents) {
    if (agent.name == name) return &agent;
  }
  return nullptr;
}

double BodyState::Yaw() const {
  const Eigen::Vector3d forward = orientation * Eigen::Vector3d::UnitX();
  return std::atan2(forward.y(), forward.x());
}

}  // namespace sim4cv::sim
