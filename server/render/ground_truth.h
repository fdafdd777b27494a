// Ground-truth 2D boxes from an instance mask: the tight box of each labelled
// object's visible pixels, and its visibility against its unoccluded silhouette.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "server/render/render_types.h"

namespace sim4cv::render {

struct LabelledObject {
  InstanceId instance = kUnlabelled;
  uint32_t object_class = 0;      // proto ObjectClass value
  uint32_t unoccluded_pixels = 0;  // from Renderer::Render
};

struct GroundTruthBox {
  InstanceId instance = kUnlabelled;
  uint32_t object_class = 0;
  uint32_t x = 0, y = 0, width = 0, height = 0;  // x + width is one past the right-most column
  uint32_t visible_pixels = 0;
  float visibility = 0.0f;  // visible / unoccluded, clamped to (0, 1]
};

// Reusable scratch space so a frame's box computation allocates nothing once
// warmed up.
class BoxExtractor {
 public:
  // Appends to `out` (cleared first) one box per object in `objects` that has
  // at least one visible pixel, ordered by instance id.
  void Extract(const uint16_t* mask, uint32_t width, uint32_t height, std::span<const LabelledObject> objects,
               std::vector<GroundTruthBox>& out);

 private:
  struct Extent {
    uint32_t x_min, y_min, x_max, y_max, count;
  };
  std::vector<Extent> extents_;  // indexed by instance id
};

}  // namespace sim4cv::render
