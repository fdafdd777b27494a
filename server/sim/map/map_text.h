// The map text format (docs/maps.md): reading and writing.
#pragma once

#include <string>

#include "server/sim/map/map.h"

namespace sim4cv::map {

// Parses map text. Throws std::invalid_argument naming the line number and
// the line as written ("map line N 'LINE': ..."); problems that belong to no
// single line (no header, no grid) name the map instead.
Map ParseMap(const std::string& text);

// Reads and parses a map file; errors are prefixed with the path.
Map LoadMapFile(const std::string& path);

// The canonical text of `map`: ParseMap(WriteMap(m)) == m up to the 0.01 m /
// 0.01 degree rounding of object lines, and WriteMap is a fixed point of
// that round trip. `comment` (may be empty, may hold several lines) is
// written as '#' lines right after the header.
std::string WriteMap(const Map& map, const std::string& comment = "");

// The character a grid row uses for one tile: '.' empty, '#' a road tile
// whose connections are what '#' infers from its neighbours, otherwise the
// connection mask as a hex digit.
char TileChar(const Map& map, TileCoord t);

// Reads a whole file; throws std::invalid_argument if it cannot be opened.
std::string ReadTextFile(const std::string& path);

}  // namespace sim4cv::map
