// Instance (and entity) ids of a map's traffic: parked cars, traffic
// lights, moving cars, walkers, each a block of consecutive ids starting at
// its field, right after the map's own objects; `end` is one past the last.
// Masks, boxes, 3D ground truth and run logs all use these
// (sim::TrafficIdsOf gives a scene's).
#pragma once

#include <cstdint>

#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::traffic {

struct TrafficIds {
  uint32_t parked = 0, lights = 0, cars = 0, walkers = 0, end = 0;
};

// The blocks for `plan` (null: no traffic, all equal to `first`) from `first` on.
inline TrafficIds IdsFrom(const TrafficPlan* plan, uint32_t first) {
  TrafficIds ids{first, first, first, first, first};
  if (!plan) return ids;
  ids.lights = ids.parked + static_cast<uint32_t>(plan->parked_cars().size());
  ids.cars = ids.lights + static_cast<uint32_t>(plan->lights().size());
  ids.walkers = ids.cars + static_cast<uint32_t>(plan->car_starts().size());
  ids.end = ids.walkers + static_cast<uint32_t>(plan->walker_starts().size());
  return ids;
}

}  // namespace sim4cv::traffic
