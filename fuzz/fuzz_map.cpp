// Fuzz target: the tile-map parser (server/sim/map/map_parser.cpp) and what a
// LoadMap or --map builds from a parsed map before the world: the lane graph
// (RoadGraph). ParseMap may refuse any text with std::invalid_argument (naming
// the line); anything else it throws, or a crash, is a finding. A map it
// accepts must survive the documented round trip: WriteMap's text parses
// again and is a fixed point (server/sim/map/map_text.h).
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "server/sim/map/map_text.h"
#include "server/sim/map/road_graph.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  sim4cv::map::Map map;
  try {
    map = sim4cv::map::ParseMap(text);
  } catch (const std::invalid_argument&) {
    return 0;  // refused, naming the line: what a bad map should get
  }
  const sim4cv::map::RoadGraph graph(map);
  const std::string written = sim4cv::map::WriteMap(map);
  const sim4cv::map::Map again = sim4cv::map::ParseMap(written);  // throws out of the fuzzer if not
  if (sim4cv::map::WriteMap(again) != written) __builtin_trap();
  return 0;
}
