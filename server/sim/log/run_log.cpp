#include "server/sim/log/run_log.h"

namespace sim4cv::runlog {

const LogEntity* RunLogHeader::FindEntity(uint32_t id) const {
  for (const LogEntity& entity : entities) {
    if (entity.id == id) return &entity;
  }
  return nullptr;
}

const LogEntity* RunLogHeader::FindEntity(const std::string& name) const {
  for (const LogEntity& entity : entities) {
    if (entity.name == name) return &entity;
  }
  return nullptr;
}

void FrameLogRecord::Clear() {
  frame_id = 0;
  sim_time = 0.0;
  entities.clear();
  tracker_boxes.clear();
  ground_truth.clear();
  controls.clear();
}

}  // namespace sim4cv::runlog
