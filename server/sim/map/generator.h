// Random maps from a seed (docs/maps.md, "Generating maps"): a connected road
// network with curves and junctions, its dressing, and a closed route. The
// same options give byte-identical text; the desert and urban forms of one
// seed share the road grid and the routes and differ only in dressing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "server/sim/map/map.h"

namespace sim4cv::map {

struct GeneratorOptions {
  uint64_t seed = 1;
  int width = 10, height = 10;  // tiles, 3..200; unused with `layout`
  double tile_size = 20.0;      // metres; unused with `layout`
  Surroundings surroundings = Surroundings::kDesert;
  std::string name = "generated";
  // A map file whose grid, tile size and routes are kept (its objects are
  // dropped); only the dressing is generated. Empty: generate the roads too.
  std::string layout;
  // Chance that a roadside slot (one per side of the road about every 10 m,
  // beside straights and curves) gets a tree whose crown overhangs the
  // road; negative: the surroundings' default (urban 0.15, desert 0).
  double roadside_trees = -1.0;
};

// Parses sim4cv_mapgen's options (docs/maps.md), without the program name
// and without --out. Throws std::invalid_argument on a bad or missing option.
GeneratorOptions ParseGeneratorArgs(const std::vector<std::string>& args);
// The canonical options that ParseGeneratorArgs reads back as `options`.
std::string GeneratorArgs(const GeneratorOptions& options);

// The road network of a width x height grid and one closed route, "loop";
// no objects, desert.
Map GenerateRoads(uint64_t seed, int width, int height, double tile_size);

// Adds houses, trees, lanterns, parks and obstacles off the road, by the
// map's surroundings. Deterministic in (map, seed, roadside_trees).
void Dress(Map& map, uint64_t seed, double roadside_trees);

Map GenerateMap(const GeneratorOptions& options);
// WriteMap(GenerateMap(options)) with the comment line
// "# sim4cv_mapgen ARGS" (kGeneratorComment + GeneratorArgs), so a shipped
// map records how to make it again.
std::string GenerateMapText(const GeneratorOptions& options);
inline constexpr const char* kGeneratorComment = "# sim4cv_mapgen ";

}  // namespace sim4cv::map
