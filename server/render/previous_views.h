// Each camera's pose one simulated frame earlier, for optical flow
// (CameraView::previous_world_from_camera). Kept for every camera every
// frame, rendered or not, so a flow frame always spans exactly one frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "server/render/render_types.h"
#include "server/sim/scene.h"

namespace sim4cv::render {

class PreviousViews {
 public:
  // The pose camera `index` had one frame earlier, if it was this camera
  // then (same name and image); otherwise `current`'s pose: no camera motion.
  Eigen::Matrix4f Of(uint32_t index, const sim::CameraSpec& spec, const CameraView& current) const {
    if (index < entries_.size()) {
      const Entry& entry = entries_[index];
      if (entry.valid && entry.name == spec.name && entry.width == current.width && entry.height == current.height &&
          entry.fov_y_deg == current.fov_y_deg) {
        return entry.world_from_camera;
      }
    }
    return current.world_from_camera;
  }

  // Records camera `index`'s view of this frame. No allocation once every
  // camera has been seen (a name no longer than before keeps its capacity).
  void Remember(uint32_t index, const sim::CameraSpec& spec, const CameraView& view) {
    if (index >= entries_.size()) entries_.resize(index + 1);
    Entry& entry = entries_[index];
    entry.valid = true;
    entry.name = spec.name;
    entry.width = view.width;
    entry.height = view.height;
    entry.fov_y_deg = view.fov_y_deg;
    entry.world_from_camera = view.world_from_camera;
  }

  // A new world: no camera has a previous frame in it.
  void Clear() {
    for (Entry& entry : entries_) entry.valid = false;
  }

 private:
  struct Entry {
    bool valid = false;
    std::string name;
    uint32_t width = 0, height = 0;
    float fov_y_deg = 0.0f;
    Eigen::Matrix4f world_from_camera = Eigen::Matrix4f::Identity();
  };
  std::vector<Entry> entries_;
};

}  // namespace sim4cv::render
