// ParseMap: one pass over the lines, keyword by keyword (docs/maps.md).
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "server/common/check.h"
#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/common/regular_file.h"
#include "server/sim/map/map_text.h"

namespace sim4cv::map {
namespace {

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

int HexValue(char c) {
  if (c >= '1' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;  // '0' is no code: a road tile must connect somewhere
}

const char* EdgeName(Edge e) {
  static const char* const kNames[] = {"north", "east", "south", "west"};
  return kNames[static_cast<int>(e)];
}

class Parser {
 public:
  Map Parse(const std::string& text) {
    std::istringstream lines(text);
    while (std::getline(lines, line_)) {
      ++line_number_;
      SIM4CV_THROW_UNLESS(line_.size() <= limits::kMaxMapLineBytes,
                          "map line " << line_number_ << " is " << line_.size() << " bytes long; a map line has at most "
                                      << limits::kMaxMapLineBytes << " (limits::kMaxMapLineBytes)");
      if (!line_.empty() && line_.back() == '\r') line_.pop_back();
      if (in_grid_ && grid_rows_.size() < static_cast<std::size_t>(map_.height)) {
        ReadGridRow();
        continue;
      }
      std::istringstream words(line_.substr(0, line_.find('#')));
      std::string keyword;
      if (in_grid_) {
        // Right after the last row, with no blank or comment line between:
        // an extra row such as "#..#" must not pass for a comment.
        SIM4CV_THROW_UNLESS(words >> keyword && keyword == "end" && !(words >> keyword),
                            Here() << "expected 'end' after " << map_.height << " grid rows");
        ResolveGrid();
        continue;
      }
      if (!(words >> keyword)) continue;
      if (!header_seen_) {
        ReadHeader(keyword, words);
        continue;
      }
      Dispatch(keyword, words);
    }
    SIM4CV_THROW_UNLESS(header_seen_, "map: no 'sim4cv-map 1' header");
    SIM4CV_THROW_UNLESS(
        !in_grid_, "map '" << map_.name << "' ends inside its grid (expected " << map_.height << " rows and 'end')");
    SIM4CV_THROW_UNLESS(!map_.name.empty(), "map has no 'name'");
    SIM4CV_THROW_UNLESS(map_.width > 0, "map '" << map_.name << "' has no grid");
    for (std::size_t i = 0; i < map_.routes.size(); ++i) CloseRoute(i);
    return map_;
  }

 private:
  // The prefix of every message about the current line.
  std::string Here() const { return "map line " + std::to_string(line_number_) + " " + Quoted(line_) + ": "; }

  void ReadHeader(const std::string& keyword, std::istringstream& words) {
    std::string version, extra;
    SIM4CV_THROW_UNLESS(keyword == "sim4cv-map", Here() << "the first line must be 'sim4cv-map 1'");
    SIM4CV_THROW_UNLESS(words >> version && !(words >> extra), Here() << "the header is 'sim4cv-map VERSION'");
    SIM4CV_THROW_UNLESS(version == "1",
                        Here() << "unsupported map format version '" << version << "' (this reader knows 1)");
    header_seen_ = true;
  }

  std::string Word(std::istringstream& words, const char* what) {
    std::string word;
    SIM4CV_THROW_UNLESS(words >> word, Here() << "missing " << what);
    return word;
  }

  void NoMore(std::istringstream& words) {
    std::string extra;
    SIM4CV_THROW_UNLESS(!(words >> extra), Here() << "unexpected '" << extra << "'");
  }

  double Number(std::istringstream& words, const char* what) {
    const std::string token = Word(words, what);
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    SIM4CV_THROW_UNLESS(end != token.c_str() && *end == '\0', Here() << "'" << token << "' is not a number");
    SIM4CV_THROW_UNLESS(std::isfinite(value), Here() << "'" << token << "' is not finite");
    return value;
  }

  int Integer(const std::string& token, const char* what) {
    int value = 0;
    const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
    SIM4CV_THROW_UNLESS(error == std::errc() && end == token.data() + token.size(),
                        Here() << "'" << token << "' is not " << what);
    return value;
  }

  void Dispatch(const std::string& keyword, std::istringstream& words) {
    using Handler = void (Parser::*)(std::istringstream&);
    struct Keyword {
      Handler read;
      bool once;  // sets one value; objects, routes and their tiles accumulate
    };
    static const std::map<std::string, Keyword> kKeywords = {
        {"name", {&Parser::ReadName, true}},
        {"tile_size", {&Parser::ReadTileSize, true}},
        {"surroundings", {&Parser::ReadSurroundings, true}},
        {"grid", {&Parser::StartGrid, true}},
        {"object", {&Parser::ReadObject, false}},
        {"route", {&Parser::StartRoute, false}},
        {"tiles", {&Parser::ReadRouteTiles, false}},
    };
    const auto it = kKeywords.find(keyword);
    SIM4CV_THROW_UNLESS(it != kKeywords.end(), Here() << "unknown keyword '" << keyword << "'");
    SIM4CV_THROW_UNLESS(!it->second.once || seen_.insert(keyword).second, Here() << "'" << keyword << "' given twice");
    (this->*it->second.read)(words);
    NoMore(words);
  }

  void ReadName(std::istringstream& words) { map_.name = Name(words, "the map's name"); }

  // Map and route names reach every client (Welcome, WorldInfo), so they
  // are as short as the names clients give.
  std::string Name(std::istringstream& words, const char* what) {
    std::string name = Word(words, what);
    SIM4CV_THROW_UNLESS(name.size() <= limits::kMaxNameBytes, Here() << what << " is " << name.size()
                                                                     << " bytes long; a name has at most "
                                                                     << limits::kMaxNameBytes
                                                                     << " (limits::kMaxNameBytes)");
    return name;
  }

  void ReadTileSize(std::istringstream& words) {
    map_.tile_size = Number(words, "the tile size");
    SIM4CV_THROW_UNLESS(map_.tile_size >= kMinTileSize, Here() << "tile_size must be >= " << kMinTileSize << " m");
    SIM4CV_THROW_UNLESS(map_.tile_size <= limits::kMaxMapTileSize, Here() << "tile_size must be <= "
                                                                          << limits::kMaxMapTileSize
                                                                          << " m (limits::kMaxMapTileSize)");
    CheckExtent();
  }

  // Called by both 'grid' and 'tile_size', whichever comes second (before
  // it, the default tile size or no grid).
  void CheckExtent() const {
    const double widest = std::max(map_.width, map_.height) * map_.tile_size;
    SIM4CV_THROW_UNLESS(widest <= limits::kMaxMapExtentMetres,
                        Here() << "the map would be " << widest << " m across (" << std::max(map_.width, map_.height)
                               << " tiles of " << map_.tile_size << " m); a map spans at most "
                               << limits::kMaxMapExtentMetres << " m each way (limits::kMaxMapExtentMetres)");
  }

  void ReadSurroundings(std::istringstream& words) {
    const std::string name = Word(words, "desert or urban");
    const auto surroundings = SurroundingsFromName(name);
    SIM4CV_THROW_UNLESS(surroundings.has_value(), Here()
                                                      << "surroundings must be desert or urban, not '" << name << "'");
    map_.surroundings = *surroundings;
  }

  void StartGrid(std::istringstream& words) {
    map_.width = Integer(Word(words, "the grid width"), "a width");
    map_.height = Integer(Word(words, "the grid height"), "a height");
    constexpr int kMaxSide = limits::kMaxMapGridSide;
    SIM4CV_THROW_UNLESS(
        map_.width >= 1 && map_.height >= 1 && map_.width <= kMaxSide && map_.height <= kMaxSide,
        Here() << "grid size must be 1.." << kMaxSide << " tiles each way (limits::kMaxMapGridSide)");
    CheckExtent();
    in_grid_ = true;
  }

  void ReadGridRow() {
    const std::string row = Trim(line_);
    SIM4CV_THROW_UNLESS(static_cast<int>(row.size()) == map_.width, Here() << "grid row " << grid_rows_.size()
                                                                           << " has " << row.size()
                                                                           << " tiles, expected " << map_.width);
    for (char c : row) {
      SIM4CV_THROW_UNLESS(c == '.' || c == '#' || HexValue(c) > 0,
                          Here() << "'" << c << "' is no tile: use '.', '#' or a connection mask 1-9, a-f");
      road_tiles_ += c == '.' ? 0 : 1;
    }
    SIM4CV_THROW_UNLESS(road_tiles_ <= limits::kMaxMapRoadTiles,
                        Here() << "the grid has " << road_tiles_ << " road tiles up to this row; a map has at most "
                               << limits::kMaxMapRoadTiles << " (limits::kMaxMapRoadTiles)");
    grid_rows_.push_back(row);
    grid_lines_.push_back({line_number_, line_});
  }

  // Turns the rows into connection masks, with each complaint naming the row.
  void ResolveGrid() {
    in_grid_ = false;
    const auto end_line = std::make_pair(line_number_, line_);
    map_.road.assign(static_cast<std::size_t>(map_.width) * map_.height, 0);
    const auto raw = [&](TileCoord t) { return map_.InGrid(t) ? grid_rows_[t.row][t.col] : '.'; };
    for (int r = 0; r < map_.height; ++r) {
      line_number_ = grid_lines_[r].first;
      line_ = grid_lines_[r].second;
      for (int c = 0; c < map_.width; ++c) {
        const TileCoord t{c, r};
        const char here = raw(t);
        if (here == '.') continue;
        EdgeMask mask = 0;
        for (Edge e : kEdges) {
          const char there = raw(Neighbour(t, e));
          const bool links_back =
              there == '#' || (there != '.' && Has(static_cast<EdgeMask>(HexValue(there)), Opposite(e)));
          const bool wanted = here == '#' ? there != '.' && links_back : Has(static_cast<EdgeMask>(HexValue(here)), e);
          if (!wanted) continue;
          SIM4CV_THROW_UNLESS(there != '.',
                              Here() << "tile " << c << "," << r << " connects " << EdgeName(e) << " to no road");
          SIM4CV_THROW_UNLESS(links_back, Here() << "tile " << c << "," << r << " connects " << EdgeName(e)
                                                 << " but its neighbour does not connect back");
          mask |= Bit(e);
        }
        SIM4CV_THROW_UNLESS(mask != 0, Here() << "road tile " << c << "," << r << " has no road neighbour");
        map_.road[map_.Index(t)] = mask;
      }
    }
    std::tie(line_number_, line_) = end_line;
  }

  void ReadObject(std::istringstream& words) {
    const std::string name = Word(words, "the object's kind");
    const auto kind = ObjectKindFromName(name);
    SIM4CV_THROW_UNLESS(kind.has_value(),
                        Here() << "unknown object kind '" << name << "' (house, tree, lantern, park, obstacle)");
    SIM4CV_THROW_UNLESS(map_.objects.size() < static_cast<std::size_t>(limits::kMaxMapObjects),
                        Here() << "a map has at most " << limits::kMaxMapObjects
                               << " objects (limits::kMaxMapObjects)");
    MapObject object;
    object.kind = *kind;
    constexpr double kReach = limits::kMaxMapObjectCoordinate;
    object.position.x() = Bounded(Number(words, "x"), kReach, "x", "m (limits::kMaxMapObjectCoordinate)");
    object.position.y() = Bounded(Number(words, "y"), kReach, "y", "m (limits::kMaxMapObjectCoordinate)");
    object.rotation_deg = Bounded(Number(words, "the rotation in degrees"), limits::kMaxMapObjectRotationDeg,
                                  "the rotation", "degrees (limits::kMaxMapObjectRotationDeg)");
    map_.objects.push_back(object);
  }

  // `value` if it lies in [-bound, bound].
  double Bounded(double value, double bound, const char* what, const char* unit_and_limit) const {
    SIM4CV_THROW_UNLESS(std::abs(value) <= bound,
                        Here() << what << " " << value << " is outside -" << bound << ".." << bound << " "
                               << unit_and_limit);
    return value;
  }

  void StartRoute(std::istringstream& words) {
    SIM4CV_THROW_UNLESS(map_.width > 0, Here() << "'route' must come after the grid");
    SIM4CV_THROW_UNLESS(map_.routes.size() < static_cast<std::size_t>(limits::kMaxMapRoutes),
                        Here() << "a map has at most " << limits::kMaxMapRoutes << " routes (limits::kMaxMapRoutes)");
    Route route;
    route.name = Name(words, "the route's name");
    const std::string shape = Word(words, "closed or open");
    SIM4CV_THROW_UNLESS(shape == "closed" || shape == "open",
                        Here() << "a route is closed or open, not '" << shape << "'");
    route.closed = shape == "closed";
    SIM4CV_THROW_UNLESS(map_.FindRoute(route.name) == nullptr, Here() << "route '" << route.name << "' defined twice");
    map_.routes.push_back(route);
    route_lines_.push_back({line_number_, line_});
  }

  void ReadRouteTiles(std::istringstream& words) {
    SIM4CV_THROW_UNLESS(!map_.routes.empty(), Here() << "'tiles' before any 'route'");
    Route& route = map_.routes.back();
    std::string token;
    while (words >> token) {
      const auto comma = token.find(',');
      SIM4CV_THROW_UNLESS(comma != std::string::npos, Here() << "'" << token << "' is not a tile COL,ROW");
      const TileCoord t{Integer(token.substr(0, comma), "a column"), Integer(token.substr(comma + 1), "a row")};
      SIM4CV_THROW_UNLESS(map_.InGrid(t), Here() << "route tile " << token << " is outside the " << map_.width << "x"
                                                 << map_.height << " grid");
      SIM4CV_THROW_UNLESS(map_.ConnectionsAt(t) != 0, Here() << "route tile " << token << " is not a road tile");
      const std::size_t n = route.tiles.size();
      SIM4CV_THROW_UNLESS(n < static_cast<std::size_t>(limits::kMaxMapRouteTiles),
                          Here() << "route '" << route.name << "' has more than " << limits::kMaxMapRouteTiles
                                 << " tiles (limits::kMaxMapRouteTiles)");
      if (n >= 1) RequireStep(route.tiles[n - 1], t);
      if (n >= 2) RequirePass(route.tiles[n - 2], route.tiles[n - 1], t);
      route.tiles.push_back(t);
    }
  }

  // Consecutive route tiles must be neighbours joined by road.
  void RequireStep(TileCoord from, TileCoord to) {
    Edge e{};
    SIM4CV_THROW_UNLESS(EdgeTowards(from, to, &e) && Has(map_.ConnectionsAt(from), e),
                        Here() << "route goes from " << from.col << "," << from.row << " to " << to.col << "," << to.row
                               << ", which the road does not join");
  }

  // A route may turn back only in a dead end.
  void RequirePass(TileCoord before, TileCoord at, TileCoord after) {
    Edge entry{}, exit{};
    EdgeTowards(at, before, &entry);
    EdgeTowards(at, after, &exit);
    SIM4CV_THROW_UNLESS(CanPass(map_.ConnectionsAt(at), entry, exit),
                        Here() << "route turns back at " << at.col << "," << at.row << ", which is a "
                               << KindName(map_.KindAt(at)) << " (only dead ends allow a U-turn)");
  }

  void CloseRoute(std::size_t index) {
    line_number_ = route_lines_[index].first;
    line_ = route_lines_[index].second;
    const Route& route = map_.routes[index];
    const std::size_t n = route.tiles.size();
    if (!route.closed) {
      SIM4CV_THROW_UNLESS(n >= 3, Here() << "an open route needs at least 3 tiles, has " << n);
      return;
    }
    SIM4CV_THROW_UNLESS(n >= 2, Here() << "a closed route needs at least 2 tiles, has " << n);
    RequireStep(route.tiles[n - 1], route.tiles[0]);
    RequirePass(route.tiles[n - 2], route.tiles[n - 1], route.tiles[0]);
    RequirePass(route.tiles[n - 1], route.tiles[0], route.tiles[1]);
  }

  Map map_;
  std::string line_;
  int line_number_ = 0;
  bool header_seen_ = false;
  bool in_grid_ = false;
  int road_tiles_ = 0;  // in the grid rows read so far
  std::set<std::string> seen_;
  std::vector<std::string> grid_rows_;
  std::vector<std::pair<int, std::string>> grid_lines_;   // number and text of each grid row
  std::vector<std::pair<int, std::string>> route_lines_;  // of each route's 'route' line
};

}  // namespace

Map ParseMap(const std::string& text) { return Parser().Parse(text); }

std::string ReadTextFile(const std::string& path) {
  // A FIFO or device is refused, never waited on (docs/reliability.md, finding 7).
  return ReadRegularFile(path, "map file", limits::kMaxMapTextBytes, "limits::kMaxMapTextBytes");
}

Map LoadMapFile(const std::string& path) {
  const std::string text = ReadTextFile(path);
  try {
    return ParseMap(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(path + ": " + e.what());
  }
}

}  // namespace sim4cv::map
