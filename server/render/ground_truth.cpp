#include "server/render/ground_truth.h"

#include <algorithm>
#include <limits>

namespace sim4cv::render {

void BoxExtractor::Extract(const uint16_t* mask, uint32_t width, uint32_t height,
                           std::span<const LabelledObject> objects, std::vector<GroundTruthBox>& out) {
  out.clear();
  InstanceId largest_id = kUnlabelled;
  for (const LabelledObject& object : objects) largest_id = std::max(largest_id, object.instance);
  if (largest_id == kUnlabelled) return;
  if (extents_.size() <= largest_id) extents_.resize(size_t{largest_id} + 1);

  // Only the requested ids are reset; pixels of other ids below largest_id may
  // accumulate into stale entries, which nobody reads before resetting them.
  for (const LabelledObject& object : objects) {
    extents_[object.instance] = {std::numeric_limits<uint32_t>::max(), std::numeric_limits<uint32_t>::max(), 0, 0, 0};
  }
  for (uint32_t y = 0; y < height; ++y) {
    const uint16_t* row = mask + size_t{y} * width;
    for (uint32_t x = 0; x < width; ++x) {
      const InstanceId id = row[x];
      if (id == kUnlabelled || id > largest_id) continue;
      Extent& extent = extents_[id];
      extent.x_min = std::min(extent.x_min, x);
      extent.x_max = std::max(extent.x_max, x);
      extent.y_min = std::min(extent.y_min, y);
      extent.y_max = std::max(extent.y_max, y);
      ++extent.count;
    }
  }

  for (const LabelledObject& object : objects) {
    if (object.instance == kUnlabelled) continue;
    Extent& extent = extents_[object.instance];
    if (extent.count == 0) continue;
    const float visibility =
        object.unoccluded_pixels == 0
            ? 1.0f
            : std::min(1.0f, static_cast<float>(extent.count) / static_cast<float>(object.unoccluded_pixels));
    out.push_back({object.instance, object.object_class, extent.x_min, extent.y_min, extent.x_max - extent.x_min + 1,
                   extent.y_max - extent.y_min + 1, extent.count, visibility});
    extent.count = 0;  // an id listed twice yields one box
  }
  std::sort(out.begin(), out.end(),
            [](const GroundTruthBox& a, const GroundTruthBox& b) { return a.instance < b.instance; });
}

}  // namespace sim4cv::render
