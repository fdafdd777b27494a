// WriteMap: the canonical text, byte for byte the same for the same Map.
#include <cstdio>
#include <sstream>

#include "server/sim/map/map_text.h"

namespace sim4cv::map {
namespace {

// Fixed-point with two decimals: printf's rounding, not the stream's locale.
std::string Fixed(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.2f", value);
  // "-0.00" and "0.00" are the same number; write one of them.
  return std::string(buffer) == "-0.00" ? "0.00" : buffer;
}

std::string Shortest(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.10g", value);
  return buffer;
}

constexpr std::size_t kTilesPerLine = 12;

}  // namespace

char TileChar(const Map& map, TileCoord t) {
  const EdgeMask mask = map.ConnectionsAt(t);
  if (mask == 0) return '.';
  EdgeMask road_neighbours = 0;
  for (Edge e : kEdges) {
    if (map.ConnectionsAt(Neighbour(t, e)) != 0) road_neighbours |= Bit(e);
  }
  return mask == road_neighbours ? '#' : "0123456789abcdef"[mask];
}

std::string WriteMap(const Map& map, const std::string& comment) {
  std::ostringstream out;
  out << "sim4cv-map 1\n";
  std::istringstream comment_lines(comment);
  for (std::string line; std::getline(comment_lines, line);) out << "# " << line << "\n";
  out << "name " << map.name << "\n";
  out << "tile_size " << Shortest(map.tile_size) << "\n";
  out << "surroundings " << SurroundingsName(map.surroundings) << "\n";
  out << "grid " << map.width << " " << map.height << "\n";
  for (int r = 0; r < map.height; ++r) {
    for (int c = 0; c < map.width; ++c) out << TileChar(map, {c, r});
    out << "\n";
  }
  out << "end\n";
  for (const Route& route : map.routes) {
    out << "route " << route.name << (route.closed ? " closed" : " open");
    for (std::size_t i = 0; i < route.tiles.size(); ++i) {
      out << (i % kTilesPerLine == 0 ? "\ntiles " : " ") << route.tiles[i].col << "," << route.tiles[i].row;
    }
    out << "\n";
  }
  for (const MapObject& object : map.objects) {
    out << "object " << ObjectKindName(object.kind) << " " << Fixed(object.position.x()) << " "
        << Fixed(object.position.y()) << " " << Fixed(object.rotation_deg) << "\n";
  }
  return out.str();
}

}  // namespace sim4cv::map
