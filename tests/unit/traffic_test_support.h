// Maps for the traffic tests: shipped ones from scenes/, and a small grid
// written here, with a road graph and a plan built on them.
#pragma once

#include <filesystem>
#include <string>

#include "server/sim/map/map_text.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::traffic::testing {

// The source tree: this file is tests/unit/traffic_test_support.h in it
// (CMake compiles with absolute paths), so no extra define is needed.
inline std::filesystem::path SourceDir() {
  return std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
}

inline map::Map LoadShipped(const std::string& relative) { return map::LoadMapFile((SourceDir() / relative).string()); }

// A 5 x 5 grid of 20 m tiles: four bends in the corners, four T-junctions
// on the sides, a crossroads in the middle, straights between.
inline map::Map GridMap() {
  return map::ParseMap(
      "sim4cv-map 1\nname grid\ntile_size 20\ngrid 5 5\n"
      "#####\n#.#.#\n#####\n#.#.#\n#####\nend\n");
}

// A map, its graph and a plan on them, built in that order.
struct TrafficWorld {
  TrafficWorld(map::Map m, const TrafficConfig& config) : map(std::move(m)), graph(map), plan(map, graph, config) {}
  map::Map map;
  map::RoadGraph graph;
  TrafficPlan plan;
};

inline TrafficConfig Config(int moving, int parked, int pedestrians, uint64_t seed = 7) {
  TrafficConfig config;
  config.moving_cars = moving;
  config.parked_cars = parked;
  config.pedestrians = pedestrians;
  config.seed = seed;
  return config;
}

}  // namespace sim4cv::traffic::testing
