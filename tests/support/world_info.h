// What the sim thread would publish for session tests: a WorldInfo naming the
// scene and its first camera, plus any extra cameras (name, square size).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "server/sim/scene.h"
#include "sim4cv.pb.h"

namespace sim4cv::testing {

inline proto::WorldInfo FirstCameraWorld(const sim::Scene& scene,
                                         const std::vector<std::pair<std::string, uint32_t>>& extra_cameras = {}) {
  proto::WorldInfo world;
  world.set_scene_name(scene.name);
  proto::CameraInfo* camera = world.add_cameras();
  camera->set_name(scene.cameras[0].name);
  camera->set_width(scene.cameras[0].width);
  camera->set_height(scene.cameras[0].height);
  for (const auto& [name, size] : extra_cameras) {
    proto::CameraInfo* extra = world.add_cameras();
    extra->set_name(name);
    extra->set_width(size);
    extra->set_height(size);
  }
  return world;
}

}  // namespace sim4cv::testing
