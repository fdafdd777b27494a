// sim4cv_maptool: road lengths and checks of map files (docs/maps.md).
#include <array>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/sim/map/map_text.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/map/validate.h"

namespace {

using namespace sim4cv::map;

constexpr const char* kUsage =
    "usage: sim4cv_maptool lengths FILE...   road length of each map and of the whole set\n"
    "       sim4cv_maptool check FILE...     parse, and check each map is one connected network\n"
    "                                        with no object but obstacles on the road\n";

int Lengths(const std::vector<std::string>& files) {
  double total = 0;
  for (const std::string& file : files) {
    const Map map = LoadMapFile(file);
    total += RoadLength(map);
    std::printf("%10.1f m  %s (%s)\n", RoadLength(map), file.c_str(), map.name.c_str());
  }
  std::printf("%10.1f m  total of %zu maps\n", total, files.size());
  return 0;
}

// "12 straight, 4 curve, ..." for the kinds present.
std::string KindCounts(const Map& map) {
  std::array<int, 6> counts{};
  for (EdgeMask mask : map.road) ++counts[static_cast<int>(KindOf(mask))];
  std::string text;
  for (int kind = 1; kind < 6; ++kind) {
    if (counts[kind] == 0) continue;
    if (!text.empty()) text += ", ";
    text += std::to_string(counts[kind]) + " " + KindName(static_cast<TileKind>(kind));
  }
  return text;
}

int Check(const std::vector<std::string>& files) {
  int failed = 0;
  for (const std::string& file : files) {
    try {
      const Map map = LoadMapFile(file);
      const RoadGraph graph(map);
      const auto problems = FindProblems(map, graph);
      for (const std::string& problem : problems) std::printf("%s: %s\n", file.c_str(), problem.c_str());
      if (!problems.empty()) {
        ++failed;
        continue;
      }
      std::printf("%s: ok: %s, %dx%d tiles of %g m (%s), %zu lane segments, %.1f m of road, %zu routes, %zu objects\n",
                  file.c_str(), map.name.c_str(), map.width, map.height, map.tile_size, KindCounts(map).c_str(),
                  graph.segments().size(), RoadLength(map), map.routes.size(), map.objects.size());
    } catch (const std::exception& e) {
      std::printf("%s\n", e.what());
      ++failed;
    }
  }
  if (failed > 0) std::printf("%d of %zu maps failed\n", failed, files.size());
  return failed > 0 ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (args.size() < 2 || (args[0] != "lengths" && args[0] != "check")) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::vector<std::string> files(args.begin() + 1, args.end());
  try {
    return args[0] == "lengths" ? Lengths(files) : Check(files);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sim4cv_maptool: %s\n", e.what());
    return 2;
  }
}
