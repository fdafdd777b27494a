// sim4cv_mapgen: writes a generated map (docs/maps.md, "Generating maps").
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/sim/map/generator.h"
#include "server/sim/map/map_text.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/map/validate.h"

namespace {

constexpr const char* kUsage =
    "usage: sim4cv_mapgen --seed N --size WxH --surroundings desert|urban --name NAME --out FILE\n"
    "                     [--tile-size METRES] [--roadside-trees CHANCE]\n"
    "       sim4cv_mapgen --from LAYOUT.map --seed N --surroundings desert|urban --name NAME --out FILE\n"
    "                     [--roadside-trees CHANCE]\n";

int Run(std::vector<std::string> args) {
  std::string out;
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] != "--out") continue;
    out = args[i + 1];
    args.erase(args.begin() + static_cast<std::ptrdiff_t>(i), args.begin() + static_cast<std::ptrdiff_t>(i) + 2);
    break;
  }
  if (out.empty()) throw std::invalid_argument("--out is required");
  const std::string text = sim4cv::map::GenerateMapText(sim4cv::map::ParseGeneratorArgs(args));
  // Whatever is written must read back and be fit to drive on.
  const sim4cv::map::Map map = sim4cv::map::ParseMap(text);
  const sim4cv::map::RoadGraph graph(map);
  for (const std::string& problem : sim4cv::map::FindProblems(map, graph)) {
    throw std::logic_error("generated map is unfit: " + problem);
  }
  std::ofstream file(out, std::ios::binary);
  file << text;
  if (!file.flush()) throw std::invalid_argument("cannot write '" + out + "'");
  std::printf("%s: %s, %dx%d tiles of %g m, %.1f m of road, %zu objects, %zu routes\n", out.c_str(), map.name.c_str(),
              map.width, map.height, map.tile_size, sim4cv::map::RoadLength(map), map.objects.size(),
              map.routes.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::fputs(kUsage, args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  try {
    return Run(args);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "sim4cv_mapgen: %s\n%s", e.what(), kUsage);
    return 2;
  }
}
