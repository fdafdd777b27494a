// The road network generator and sim4cv_mapgen's options.
//
// Roads run along a lattice of grid lines: random columns and rows 2-4 tiles
// apart (so blocks between roads are 1-3 tiles wide and two roads never
// touch sideways). A random spanning tree of the lattice keeps the network
// connected; every leaf then gets one more street so no road dead-ends, a
// few more streets add loops, and some streets between two junctions are
// dropped again so that junctions become bends. Lattice nodes of degree 2
// become straights or curves, degree 3 and 4 T-junctions and crossroads.
#include "server/sim/map/generator.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <numeric>
#include <set>
#include <stdexcept>
#include <utility>
#include <sstream>

#include "server/common/check.h"
#include "server/common/limits.h"
#include "server/sim/map/map_text.h"
#include "server/sim/map/prng.h"

namespace sim4cv::map {
namespace {

constexpr double kExtraStreetChance = 0.12;  // per unused street, after the tree: extra loops
constexpr double kThinChance = 0.6;          // per street between two junctions: turns both into bends
constexpr int kMaxLatticeAttempts = 64;      // lattices drawn for one seed before a grid counts as too large

// Grid lines along one axis of n tiles: 2 to 4 apart, at least 3 of them
// when n >= 5 (so a 6x6 grid or larger can hold a junction).
std::vector<int> PickLines(Prng& rng, int n) {
  const std::size_t wanted = n >= 5 ? 3 : 2;
  for (int attempt = 0; attempt < 16; ++attempt) {
    std::vector<int> lines = {rng.UniformInt(0, 1)};
    for (int next = lines.back() + rng.UniformInt(2, 4); next <= n - 1; next = lines.back() + rng.UniformInt(2, 4)) {
      lines.push_back(next);
    }
    if (lines.size() >= wanted) return lines;
  }
  std::vector<int> lines;
  for (int x = 0; x <= n - 1; x += 2) lines.push_back(x);
  return lines;
}

// The streets that may be built: between neighbouring crossings of the grid lines.
struct Lattice {
  std::vector<int> xs, ys;  // columns and rows of the grid lines
  struct Street {
    int a = 0, b = 0;  // node indices, a < b
    bool used = false, in_tree = false;
  };
  std::vector<Street> streets;

  int nodes() const { return static_cast<int>(xs.size() * ys.size()); }
  TileCoord Tile(int node) const { return {xs[node % xs.size()], ys[node / xs.size()]}; }

  std::vector<int> Degrees() const {
    std::vector<int> degree(nodes(), 0);
    for (const Street& s : streets) {
      if (s.used) ++degree[s.a], ++degree[s.b];
    }
    return degree;
  }
  bool HasJunction() const {
    const auto degree = Degrees();
    return *std::max_element(degree.begin(), degree.end()) >= 3;
  }
  // Marks a breadth-first spanning tree of the used streets from node 0;
  // returns whether it reaches every node.
  bool MarkTree() {
    std::vector<bool> reached(nodes(), false);
    std::vector<int> queue = {0};
    reached[0] = true;
    for (Street& s : streets) s.in_tree = false;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      for (Street& s : streets) {
        if (!s.used || (s.a != queue[head] && s.b != queue[head])) continue;
        const int other = s.a == queue[head] ? s.b : s.a;
        if (reached[other]) continue;
        reached[other] = s.in_tree = true;
        queue.push_back(other);
      }
    }
    return static_cast<int>(queue.size()) == nodes();
  }
  // Random indices of the streets that pass `wanted`.
  template <typename Predicate>
  std::vector<std::size_t> Shuffled(Prng& rng, Predicate wanted) const {
    std::vector<std::size_t> picked;
    for (std::size_t i = 0; i < streets.size(); ++i) {
      if (wanted(streets[i])) picked.push_back(i);
    }
    for (std::size_t i = picked.size(); i > 1; --i)
      std::swap(picked[i - 1], picked[rng.UniformInt(0, static_cast<int>(i) - 1)]);
    return picked;
  }
};

int FindRoot(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The tiles from node a's tile up to (not including) node b's tile.
std::vector<TileCoord> StreetTiles(const Lattice& lattice, int a, int b) {
  const TileCoord from = lattice.Tile(a), to = lattice.Tile(b);
  const int dc = (to.col > from.col) - (to.col < from.col), dr = (to.row > from.row) - (to.row < from.row);
  std::vector<TileCoord> tiles;
  for (TileCoord t = from; !(t == to); t = {t.col + dc, t.row + dr}) tiles.push_back(t);
  return tiles;
}

// Drops streets, in random order, whose both ends stay at degree >= 2 (no
// dead end), when `drop()` says so and the network stays in one piece and
// keeps a junction.
template <typename Drop>
void Thin(Lattice& lattice, Prng& rng, Drop drop) {
  for (std::size_t i : lattice.Shuffled(rng, [](const Lattice::Street& s) { return s.used; })) {
    Lattice::Street& s = lattice.streets[i];
    const auto degree = lattice.Degrees();
    if (degree[s.a] < 3 || degree[s.b] < 3 || !drop()) continue;
    s.used = false;
    if (!lattice.MarkTree() || !lattice.HasJunction()) s.used = true;
  }
}

// The tiles the used streets cover: the map's road tiles.
int RoadTileCount(const Lattice& lattice) {
  std::set<std::pair<int, int>> tiles;
  for (const auto& s : lattice.streets) {
    if (!s.used) continue;
    for (const TileCoord& t : StreetTiles(lattice, s.a, s.b)) tiles.insert({t.col, t.row});
    tiles.insert({lattice.Tile(s.b).col, lattice.Tile(s.b).row});
  }
  return static_cast<int>(tiles.size());
}

Lattice BuildLattice(Prng& rng, int width, int height) {
  Lattice lattice{PickLines(rng, width), PickLines(rng, height), {}};
  const int nx = static_cast<int>(lattice.xs.size());
  for (int node = 0; node < lattice.nodes(); ++node) {
    if (node % nx + 1 < nx) lattice.streets.push_back({node, node + 1});
    if (node + nx < lattice.nodes()) lattice.streets.push_back({node, node + nx});
  }
  // Randomised Kruskal: a spanning tree, so every node is reached.
  std::vector<int> parent(lattice.nodes());
  std::iota(parent.begin(), parent.end(), 0);
  for (std::size_t i : lattice.Shuffled(rng, [](const Lattice::Street&) { return true; })) {
    Lattice::Street& s = lattice.streets[i];
    const int ra = FindRoot(parent, s.a), rb = FindRoot(parent, s.b);
    if (ra != rb) parent[ra] = rb, s.used = true;
  }
  // No dead ends: a leaf gets one more street.
  for (int node = 0; node < lattice.nodes(); ++node) {
    if (lattice.Degrees()[node] != 1) continue;
    const auto unused =
        lattice.Shuffled(rng, [&](const Lattice::Street& s) { return !s.used && (s.a == node || s.b == node); });
    if (!unused.empty()) lattice.streets[unused[0]].used = true;
  }
  for (auto& s : lattice.streets) {
    if (!s.used && rng.Chance(kExtraStreetChance)) s.used = true;
  }
  // Fewer junctions, more bends.
  Thin(lattice, rng, [&] { return rng.Chance(kThinChance); });
  // A single ring has no junction; one more street gives it two T's.
  if (!lattice.HasJunction()) {
    const auto unused = lattice.Shuffled(rng, [](const Lattice::Street& s) { return !s.used; });
    if (!unused.empty()) lattice.streets[unused[0]].used = true;
  }
  // A dense large grid can exceed what a map may hold: thin it further, as
  // far as the rules allow (a network that fits is left as it was, so the
  // maps made before this rule come out the same).
  if (RoadTileCount(lattice) > limits::kMaxMapRoadTiles) {
    Thin(lattice, rng, [&] { return RoadTileCount(lattice) > limits::kMaxMapRoadTiles; });
  }
  SIM4CV_DEMAND(lattice.MarkTree());
  return lattice;
}

// The longest cycle made of one non-tree street and the tree path between
// its ends, as tiles, counter-clockwise seen from above.
Route LongestLoop(const Map& map, const Lattice& lattice) {
  std::vector<std::vector<int>> tree(lattice.nodes());
  for (const auto& s : lattice.streets) {
    if (s.in_tree) tree[s.a].push_back(s.b), tree[s.b].push_back(s.a);
  }
  Route best{"loop", true, {}};
  for (const auto& s : lattice.streets) {
    if (!s.used || s.in_tree) continue;
    std::vector<int> parent(lattice.nodes(), -1), stack = {s.a};
    parent[s.a] = s.a;
    while (!stack.empty()) {
      const int node = stack.back();
      stack.pop_back();
      for (int next : tree[node]) {
        if (parent[next] < 0) parent[next] = node, stack.push_back(next);
      }
    }
    std::vector<int> cycle = {s.b};  // b back along the tree to a, then the street a-b closes it
    while (cycle.back() != s.a) cycle.push_back(parent[cycle.back()]);
    Route route{"loop", true, {}};
    for (std::size_t i = 0; i < cycle.size(); ++i) {
      const auto tiles = StreetTiles(lattice, cycle[i], cycle[(i + 1) % cycle.size()]);
      route.tiles.insert(route.tiles.end(), tiles.begin(), tiles.end());
    }
    if (route.tiles.size() > best.tiles.size()) best = route;
  }
  SIM4CV_DEMAND(!best.tiles.empty());  // every node has degree >= 2, so there is a cycle
  double area = 0;                     // shoelace over the tile centres; > 0 is counter-clockwise
  for (std::size_t i = 0; i < best.tiles.size(); ++i) {
    const auto p = map.TileCentre(best.tiles[i]), q = map.TileCentre(best.tiles[(i + 1) % best.tiles.size()]);
    area += p.x() * q.y() - q.x() * p.y();
  }
  if (area < 0) std::reverse(best.tiles.begin(), best.tiles.end());
  // Start on a straight, where a car can be put down cleanly.
  const std::size_t n = best.tiles.size();
  for (std::size_t i = 0; i < n; ++i) {
    Edge in{}, out{};
    EdgeTowards(best.tiles[i], best.tiles[(i + n - 1) % n], &in);
    EdgeTowards(best.tiles[i], best.tiles[(i + 1) % n], &out);
    if (out == Opposite(in)) {
      std::rotate(best.tiles.begin(), best.tiles.begin() + static_cast<std::ptrdiff_t>(i), best.tiles.end());
      break;
    }
  }
  return best;
}

template <typename Number>
Number Parse(const std::string& option, const std::string& text) {
  Number value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  SIM4CV_THROW_UNLESS(error == std::errc() && end == text.data() + text.size() && !text.empty(),
                      option << " wants a number, not '" << text << "'");
  return value;
}

std::string Shortest(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", value);
  return buffer;
}

}  // namespace

GeneratorOptions ParseGeneratorArgs(const std::vector<std::string>& args) {
  GeneratorOptions options;
  bool seed = false, size = false, surroundings = false, name = false;
  for (std::size_t i = 0; i < args.size(); i += 2) {
    const std::string& option = args[i];
    SIM4CV_THROW_UNLESS(i + 1 < args.size(), option << " needs a value");
    const std::string& value = args[i + 1];
    if (option == "--seed") {
      options.seed = Parse<uint64_t>(option, value), seed = true;
    } else if (option == "--size") {
      const auto x = value.find('x');
      SIM4CV_THROW_UNLESS(x != std::string::npos, "--size wants WIDTHxHEIGHT, not '" << value << "'");
      options.width = Parse<int>(option, value.substr(0, x));
      options.height = Parse<int>(option, value.substr(x + 1));
      size = true;
    } else if (option == "--surroundings") {
      const auto s = SurroundingsFromName(value);
      SIM4CV_THROW_UNLESS(s.has_value(), "--surroundings is desert or urban, not '" << value << "'");
      options.surroundings = *s, surroundings = true;
    } else if (option == "--name") {
      options.name = value, name = true;
    } else if (option == "--tile-size") {
      options.tile_size = Parse<double>(option, value);
    } else if (option == "--from") {
      options.layout = value;
    } else if (option == "--roadside-trees") {
      options.roadside_trees = Parse<double>(option, value);
      SIM4CV_THROW_UNLESS(options.roadside_trees >= 0 && options.roadside_trees <= 1, "--roadside-trees is 0..1");
    } else {
      SIM4CV_THROW_UNLESS(false, "unknown option '" << option << "'");
    }
  }
  SIM4CV_THROW_UNLESS(seed && surroundings && name, "--seed, --surroundings and --name are required");
  SIM4CV_THROW_UNLESS(size != !options.layout.empty(), "give either --size or --from");
  SIM4CV_THROW_UNLESS(options.width >= 3 && options.height >= 3 && options.width <= 200 && options.height <= 200,
                      "--size must be 3x3 to 200x200, not " << options.width << "x" << options.height);
  SIM4CV_THROW_UNLESS(options.tile_size >= kMinTileSize && options.tile_size <= limits::kMaxMapTileSize,
                      "--tile-size must be " << kMinTileSize << ".." << limits::kMaxMapTileSize
                                             << " (limits::kMaxMapTileSize)");
  // What the daemon would refuse to load is not generated (docs/maps.md, "Limits").
  SIM4CV_THROW_UNLESS(std::max(options.width, options.height) * options.tile_size <= limits::kMaxMapExtentMetres,
                      "--size and --tile-size make a map wider than " << limits::kMaxMapExtentMetres
                                                                      << " m (limits::kMaxMapExtentMetres)");
  SIM4CV_THROW_UNLESS(!options.name.empty() && options.name.find_first_of(" \t#") == std::string::npos,
                      "--name must be one word without '#'");
  return options;
}

std::string GeneratorArgs(const GeneratorOptions& options) {
  std::ostringstream out;
  if (!options.layout.empty()) {
    out << "--from " << options.layout;
  } else {
    out << "--size " << options.width << "x" << options.height;
    if (options.tile_size != 20.0) out << " --tile-size " << Shortest(options.tile_size);
  }
  out << " --seed " << options.seed << " --surroundings " << SurroundingsName(options.surroundings) << " --name "
      << options.name;
  if (options.roadside_trees >= 0) out << " --roadside-trees " << Shortest(options.roadside_trees);
  return out.str();
}

Map GenerateRoads(uint64_t seed, int width, int height, double tile_size) {
  SIM4CV_THROW_UNLESS(width >= 3 && height >= 3, "a generated map needs at least 3x3 tiles");
  Prng rng(seed);
  Lattice lattice = BuildLattice(rng, width, height);
  // Where thinning could not bring a network within the limit, the next
  // lattice the seed's generator draws is tried (other lines, other streets).
  for (int attempt = 1; RoadTileCount(lattice) > limits::kMaxMapRoadTiles; ++attempt) {
    if (attempt == kMaxLatticeAttempts) {
      throw std::invalid_argument("no road network of " + std::to_string(width) + "x" + std::to_string(height) +
                                  " tiles within " + std::to_string(limits::kMaxMapRoadTiles) +
                                  " road tiles (a map's limit) was found for seed " + std::to_string(seed) +
                                  " in " + std::to_string(kMaxLatticeAttempts) + " tries; use a smaller grid");
    }
    lattice = BuildLattice(rng, width, height);
  }
  Map map;
  map.name = "generated";
  map.tile_size = tile_size;
  map.width = width;
  map.height = height;
  map.road.assign(static_cast<std::size_t>(width) * height, 0);
  for (const auto& s : lattice.streets) {
    if (!s.used) continue;
    auto tiles = StreetTiles(lattice, s.a, s.b);
    tiles.push_back(lattice.Tile(s.b));
    for (std::size_t i = 0; i + 1 < tiles.size(); ++i) {
      Edge e{};
      EdgeTowards(tiles[i], tiles[i + 1], &e);
      map.road[map.Index(tiles[i])] |= Bit(e);
      map.road[map.Index(tiles[i + 1])] |= Bit(Opposite(e));
    }
  }
  map.routes.push_back(LongestLoop(map, lattice));
  return map;
}

Map GenerateMap(const GeneratorOptions& options) {
  Map map;
  if (options.layout.empty()) {
    map = GenerateRoads(options.seed, options.width, options.height, options.tile_size);
  } else {
    map = LoadMapFile(options.layout);
    map.objects.clear();
  }
  map.name = options.name;
  map.surroundings = options.surroundings;
  Dress(map, options.seed, options.roadside_trees);
  return map;
}

std::string GenerateMapText(const GeneratorOptions& options) {
  return WriteMap(GenerateMap(options), "sim4cv_mapgen " + GeneratorArgs(options));
}

}  // namespace sim4cv::map
