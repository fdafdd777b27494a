// Unit tests of the map text format (server/sim/map/map_parser.cpp, map_writer.cpp).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "server/common/limits.h"
#include "server/sim/map/map_text.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/map_test_support.h"

namespace sim4cv::map {
namespace {

using testing::MapText;
using testing::ParseError;
using testing::ParseRows;

TEST(MapParserTest, ReadsEveryKeyword) {
  const Map map = ParseMap(
      "# a comment before the header\n"
      "sim4cv-map 1\r\n"
      "name town   # trailing comment\n"
      "\n"
      "tile_size 25\n"
      "surroundings urban\n"
      "grid 3 2\n"
      "###\n"
      "  ###  \n"
      "end\n"
      "route ring closed\n"
      "tiles 0,0 1,0 2,0\n"
      "tiles 2,1 1,1 0,1\n"
      "object house 1.5 -2 90\n"
      "object tree 3 4 0\n");
  EXPECT_EQ(map.name, "town");
  EXPECT_EQ(map.tile_size, 25.0);
  EXPECT_EQ(map.surroundings, Surroundings::kUrban);
  ASSERT_EQ(map.width, 3);
  ASSERT_EQ(map.height, 2);
  EXPECT_EQ(map.KindAt({0, 0}), TileKind::kCurve);
  EXPECT_EQ(map.KindAt({1, 0}), TileKind::kTJunction);
  ASSERT_EQ(map.routes.size(), 1u);
  EXPECT_EQ(map.routes[0].name, "ring");
  EXPECT_TRUE(map.routes[0].closed);
  EXPECT_EQ(map.routes[0].tiles.size(), 6u);
  EXPECT_EQ(map.routes[0].tiles[3], (TileCoord{2, 1}));
  ASSERT_EQ(map.objects.size(), 2u);
  EXPECT_EQ(map.objects[0].kind, ObjectKind::kHouse);
  EXPECT_EQ(map.objects[0].position, Eigen::Vector2d(1.5, -2));
  EXPECT_EQ(map.objects[0].rotation_deg, 90.0);
  EXPECT_EQ(map.objects[1].kind, ObjectKind::kTree);
}

TEST(MapParserTest, DefaultsAndGridPlacement) {
  const Map map = ParseRows({"##", "##"});
  EXPECT_EQ(map.tile_size, 20.0);
  EXPECT_EQ(map.surroundings, Surroundings::kDesert);
  // Centred on the origin, row 0 north: tile 0,0 is the north-west one.
  testing::ExpectNear(map.TileCentre({0, 0}), {-10, 10});
  testing::ExpectNear(map.TileCentre({1, 1}), {10, -10});
  EXPECT_EQ(map.TileAt({-0.1, 0.1}), (TileCoord{0, 0}));
  EXPECT_EQ(map.TileAt({19.9, -19.9}), (TileCoord{1, 1}));
}

// Kind inference for all 16 neighbour patterns of the centre of a 3x3 grid
// (its road neighbours are dead ends with only the link back).
TEST(MapParserTest, InfersKindFromEachNeighbourPattern) {
  for (EdgeMask mask = 1; mask < 16; ++mask) {
    std::string rows[3] = {"...", ".#.", "..."};
    if (Has(mask, Edge::kNorth)) rows[0][1] = '#';
    if (Has(mask, Edge::kEast)) rows[1][2] = '#';
    if (Has(mask, Edge::kSouth)) rows[2][1] = '#';
    if (Has(mask, Edge::kWest)) rows[1][0] = '#';
    const Map map = ParseRows({rows[0].c_str(), rows[1].c_str(), rows[2].c_str()});
    EXPECT_EQ(map.ConnectionsAt({1, 1}), mask) << "mask " << int(mask);
    const int count = CountEdges(mask);
    const bool opposite_pair = mask == 0b0101 || mask == 0b1010;
    const TileKind expected = count == 1      ? TileKind::kDeadEnd
                              : count == 3    ? TileKind::kTJunction
                              : count == 4    ? TileKind::kCrossroads
                              : opposite_pair ? TileKind::kStraight
                                              : TileKind::kCurve;
    EXPECT_EQ(map.KindAt({1, 1}), expected) << "mask " << int(mask);
  }
}

TEST(MapParserTest, IsolatedRoadTileNamesItsRow) {
  const std::string message = ParseError(MapText({"...", ".#.", "..."}));
  EXPECT_EQ(message, "map line 6 '.#.': road tile 1,1 has no road neighbour");
}

TEST(MapParserTest, ExplicitCodesKeepParallelRoadsApart) {
  // 2 = east, 8 = west, a = east+west: two separate streets one above the other.
  const Map apart = ParseRows({"2aa8", "2aa8"});
  EXPECT_EQ(apart.KindAt({1, 0}), TileKind::kStraight);
  EXPECT_EQ(apart.KindAt({0, 1}), TileKind::kDeadEnd);
  EXPECT_EQ(CountRoadComponents(apart), 2);
  // '#' beside codes links to them only where the code links back: a ring.
  const Map ring = ParseRows({"#aa#", "#aa#"});
  EXPECT_EQ(ring.ConnectionsAt({0, 0}), Bit(Edge::kEast) | Bit(Edge::kSouth));
  EXPECT_EQ(ring.KindAt({1, 1}), TileKind::kStraight);
  EXPECT_EQ(CountRoadComponents(ring), 1);
  EXPECT_EQ(ParseError(MapText({"2."})), "map line 5 '2.': tile 0,0 connects east to no road");
  EXPECT_EQ(ParseError(MapText({"24", ".#"})),
            "map line 5 '24': tile 0,0 connects east but its neighbour does not connect back");
}

struct BadLine {
  std::vector<std::string> lines;
  int line;             // 1-based line the message must name
  std::string message;  // what must follow "map line N 'LINE': "
};

TEST(MapParserTest, EveryErrorNamesItsLine) {
  const std::vector<std::string> head = {"sim4cv-map 1", "name t", "grid 3 1", "###", "end"};
  const auto with = [&](std::vector<std::string> tail) {
    std::vector<std::string> lines = head;
    lines.insert(lines.end(), tail.begin(), tail.end());
    return lines;
  };
  const std::vector<BadLine> cases = {
      {{"name t"}, 1, "the first line must be 'sim4cv-map 1'"},
      {{"sim4cv-map 2"}, 1, "unsupported map format version '2' (this reader knows 1)"},
      {{"sim4cv-map"}, 1, "the header is 'sim4cv-map VERSION'"},
      {with({"colour red"}), 6, "unknown keyword 'colour'"},
      {with({"name u"}), 6, "'name' given twice"},
      {with({"tile_size 10"}), 6, "tile_size must be >= 12 m"},
      {with({"tile_size ten"}), 6, "'ten' is not a number"},
      {with({"tile_size inf"}), 6, "'inf' is not finite"},
      {with({"tile_size 20 30"}), 6, "unexpected '30'"},
      {with({"surroundings jungle"}), 6, "surroundings must be desert or urban, not 'jungle'"},
      {{"sim4cv-map 1", "grid 0 2"}, 2, "grid size must be 1..166 tiles each way (limits::kMaxMapGridSide)"},
      {{"sim4cv-map 1", "grid 3 x"}, 2, "'x' is not a height"},
      {{"sim4cv-map 1", "grid 3 2", "###", "##"}, 4, "grid row 1 has 2 tiles, expected 3"},
      {{"sim4cv-map 1", "grid 3 1", "#x#"}, 3, "'x' is no tile: use '.', '#' or a connection mask 1-9, a-f"},
      {{"sim4cv-map 1", "grid 3 1", "###", "###"}, 4, "expected 'end' after 1 grid rows"},
      {with({"object car 1 2 3"}), 6, "unknown object kind 'car' (house, tree, lantern, park, obstacle)"},
      {with({"object tree 1 2"}), 6, "missing the rotation in degrees"},
      {with({"object tree 1 2 3 4"}), 6, "unexpected '4'"},
      {{"sim4cv-map 1", "route r closed"}, 2, "'route' must come after the grid"},
      {with({"route r round"}), 6, "a route is closed or open, not 'round'"},
      {with({"tiles 0,0"}), 6, "'tiles' before any 'route'"},
      {with({"route r open", "tiles 0;0"}), 7, "'0;0' is not a tile COL,ROW"},
      {with({"route r open", "tiles 3,0"}), 7, "route tile 3,0 is outside the 3x1 grid"},
      {{"sim4cv-map 1", "grid 3 2", "###", "..#", "end", "route r open", "tiles 0,1"},
       7,
       "route tile 0,1 is not a road tile"},
      {with({"route r open", "tiles 0,0 2,0"}), 7, "route goes from 0,0 to 2,0, which the road does not join"},
      {with({"route r open", "tiles 0,0 1,0 0,0"}), 7,
       "route turns back at 1,0, which is a straight (only dead ends allow a U-turn)"},
      {with({"route r closed", "tiles 0,0 1,0 2,0"}), 6, "route goes from 2,0 to 0,0, which the road does not join"},
      {with({"route r open", "tiles 0,0 1,0"}), 6, "an open route needs at least 3 tiles, has 2"},
      {with({"route r closed"}), 6, "a closed route needs at least 2 tiles, has 0"},
      {with({"route r open", "tiles 0,0 1,0 2,0", "route r closed"}), 8, "route 'r' defined twice"},
      // Limits (server/common/limits.h, maps): every number that sizes what loading builds.
      {with({"tile_size 3e9"}), 6, "tile_size must be <= 50 m (limits::kMaxMapTileSize)"},
      {with({"tile_size 1e300"}), 6, "tile_size must be <= 50 m (limits::kMaxMapTileSize)"},
      {{"sim4cv-map 1", "grid 1000 1000"}, 2, "grid size must be 1..166 tiles each way (limits::kMaxMapGridSide)"},
      {{"sim4cv-map 1", "grid 101 3"}, 2,
       "the map would be 2020 m across (101 tiles of 20 m); a map spans at most 2000 m each way "
       "(limits::kMaxMapExtentMetres)"},
      {{"sim4cv-map 1", "grid 41 1", std::string(41, '.'), "end", "tile_size 50"}, 5,
       "the map would be 2050 m across (41 tiles of 50 m); a map spans at most 2000 m each way "
       "(limits::kMaxMapExtentMetres)"},
      {with({"object tree 2000.5 0 0"}), 6, "x 2000.5 is outside -2000..2000 m (limits::kMaxMapObjectCoordinate)"},
      {with({"object tree 0 -1e9 0"}), 6, "y -1e+09 is outside -2000..2000 m (limits::kMaxMapObjectCoordinate)"},
      {with({"object tree 0 0 400"}), 6, "the rotation 400 is outside -360..360 degrees (limits::kMaxMapObjectRotationDeg)"},
  };
  for (const BadLine& c : cases) {
    std::string text;
    for (const std::string& line : c.lines) text += line + "\n";
    EXPECT_EQ(ParseError(text), "map line " + std::to_string(c.line) + " '" + c.lines[c.line - 1] + "': " + c.message);
  }
}

// Counts bounded by limits::kMaxMap*: one more than the limit is refused on
// the line that goes over it; the limit itself is accepted.
TEST(MapParserTest, CountsAreBounded) {
  // Road tiles: 16 rows of 16 '#' is exactly kMaxMapRoadTiles (256); a 17th row goes over.
  const auto grid = [](int rows) {
    std::string text = "sim4cv-map 1\nname t\ngrid 16 " + std::to_string(rows) + "\n";
    for (int r = 0; r < rows; ++r) text += std::string(16, '#') + "\n";
    return text + "end\n";
  };
  EXPECT_EQ(ParseMap(grid(16)).road.size(), 256u);
  EXPECT_EQ(ParseError(grid(17)), "map line 20 '################': the grid has 272 road tiles up to this row; a map "
                                  "has at most 256 (limits::kMaxMapRoadTiles)");

  const std::string head = "sim4cv-map 1\nname t\ngrid 3 1\n###\nend\n";
  std::string objects = head;
  for (int i = 0; i < limits::kMaxMapObjects; ++i) objects += "object tree 0 30 0\n";
  EXPECT_EQ(ParseMap(objects).objects.size(), static_cast<std::size_t>(limits::kMaxMapObjects));
  EXPECT_EQ(ParseError(objects + "object tree 0 30 0\n"),
            "map line 2006 'object tree 0 30 0': a map has at most 2000 objects (limits::kMaxMapObjects)");

  std::string routes = "sim4cv-map 1\nname t\ngrid 2 1\n##\nend\n";
  for (int i = 0; i < limits::kMaxMapRoutes; ++i) routes += "route r" + std::to_string(i) + " closed\ntiles 0,0 1,0\n";
  EXPECT_EQ(ParseMap(routes).routes.size(), static_cast<std::size_t>(limits::kMaxMapRoutes));
  EXPECT_EQ(ParseError(routes + "route x closed\n"),
            "map line 134 'route x closed': a map has at most 64 routes (limits::kMaxMapRoutes)");

  EXPECT_NE(ParseError(head + "route " + std::string(65, 'r') + " closed\n")
                .find("the route's name is 65 bytes long; a name has at most 64 (limits::kMaxNameBytes)"),
            std::string::npos);

  // A shuttle between two dead ends, back and forth, over the route tile limit.
  std::string shuttle = "sim4cv-map 1\nname t\ngrid 2 1\n##\nend\nroute s closed\n";
  for (int i = 0; i < limits::kMaxMapRouteTiles / 2 + 1; ++i) shuttle += "tiles 0,0 1,0\n";
  EXPECT_NE(ParseError(shuttle).find("route 's' has more than 1024 tiles (limits::kMaxMapRouteTiles)"),
            std::string::npos);
}

TEST(MapParserTest, WholeMapErrorsNameTheMap) {
  EXPECT_EQ(ParseError(""), "map: no 'sim4cv-map 1' header");
  EXPECT_EQ(ParseError("sim4cv-map 1\ngrid 1 1\n.\nend\n"), "map has no 'name'");
  EXPECT_EQ(ParseError("sim4cv-map 1\nname a\n"), "map 'a' has no grid");
  EXPECT_EQ(ParseError("sim4cv-map 1\nname a\ngrid 2 2\n##\n"),
            "map 'a' ends inside its grid (expected 2 rows and 'end')");
}

TEST(MapParserTest, ClosedRouteThroughDeadEndsMayTurnBack) {
  // Two dead ends facing each other: out and back is a closed route.
  const Map map = ParseRows({"##"}, 20, "route shuttle closed\ntiles 0,0 1,0\n");
  EXPECT_EQ(map.routes[0].tiles.size(), 2u);
}

TEST(MapWriterTest, WriteIsAFixedPointOfTheRoundTrip) {
  const std::string text = MapText({"#aa#", "#aa#", "#..."}, 14,
                                   "route r closed\ntiles 0,0 1,0 2,0 3,0 3,1 2,1 1,1 0,1\n"
                                   "object lantern 1.005 -0.001 359.999\nobject park 3 4 0\n");
  const Map map = ParseMap(text);
  const std::string written = WriteMap(map, "first line\nsecond line");
  const Map again = ParseMap(written);
  EXPECT_EQ(again.road, map.road);
  EXPECT_EQ(again.tile_size, 14.0);
  EXPECT_EQ(again.routes[0].tiles, map.routes[0].tiles);
  EXPECT_EQ(WriteMap(again, "first line\nsecond line"), written);
  EXPECT_NE(written.find("sim4cv-map 1\n# first line\n# second line\nname test\n"), std::string::npos) << written;
  EXPECT_NE(written.find("grid 4 3\n#aa#\n#aa#\n#...\nend\n"), std::string::npos) << written;
  EXPECT_NE(written.find("object lantern 1.00 0.00 360.00\n"), std::string::npos) << written;
}

TEST(MapWriterTest, TileCharIsHashWhereInferenceAgrees) {
  const Map apart = ParseRows({"2aa8", "2aa8", "...."});
  EXPECT_EQ(TileChar(apart, {0, 0}), '2');  // a '#' would link to the street below
  EXPECT_EQ(TileChar(apart, {1, 1}), 'a');
  EXPECT_EQ(TileChar(apart, {1, 2}), '.');
  const Map ring = ParseRows({"#aa#", "#aa#"});
  EXPECT_EQ(TileChar(ring, {0, 0}), '#');
  EXPECT_EQ(TileChar(ring, {1, 0}), 'a');
}

}  // namespace
}  // namespace sim4cv::map
