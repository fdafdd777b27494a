#include "server/render/road_meshes.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <iterator>
#include <vector>

#include "protocol/semantic_classes.h"
#include "server/common/check.h"
#include "server/render/map_mesh_util.h"

namespace sim4cv::render {
namespace {

using map::EdgeMask;
using map::LaneSegment;
using map::Piece;
using mapmesh::AddTriangle;
using mapmesh::AddVertex;

// Lateral offsets are measured from a lane's centre line, positive to its
// left: the lane's right edge is at -2 m, the road's centre line at +2 m and
// the far edge of the two-lane road at +6 m.
constexpr double kLaneEdge = -map::kLaneWidth / 2;
constexpr double kRoadCentre = map::kLaneWidth / 2;
constexpr double kFarEdge = kRoadCentre + map::kLaneWidth;

constexpr double kLineWidth = 0.15;          // m, every painted line
constexpr double kEdgeLineInset = 0.10;      // m between the asphalt's edge and the edge line
constexpr double kDashPeriod = 6.0;          // m, about: each piece holds whole periods, so dashes line up across tiles
constexpr double kSidewalkWidth = 2.2;       // m: roadside lanterns (0.9 m off the edge) and trees (1.6 m) stand on it
constexpr double kShoulderWidth = 1.0;       // m of gravel beside desert roads
constexpr double kCrosswalkLength = 3.0;     // m along the road, at most
constexpr double kCrosswalkFromSide = 0.5;   // m between the tile side and the crosswalk
constexpr double kCrosswalkStripe = 0.5;     // m wide, and as wide as the gaps
constexpr double kCrosswalkEdgeClear = 0.5;  // m kept clear of the road edge (and its edge line)
constexpr double kMaxSagitta = 0.08;         // m between an arc and its chords, on the road's outside
constexpr double kMaxRowSpacing = 5.0;       // m between vertex rows, so colour noise has vertices to vary on

const Eigen::Vector3f kAsphalt(0.055f, 0.055f, 0.06f);
const Eigen::Vector3f kWhitePaint(0.80f, 0.80f, 0.76f);
const Eigen::Vector3f kYellowPaint(0.80f, 0.55f, 0.06f);  // desert centre lines, as on rural highways
const Eigen::Vector3f kPavement(0.34f, 0.33f, 0.31f);
const Eigen::Vector3f kCurbStone(0.55f, 0.55f, 0.53f);
const Eigen::Vector3f kGravel(0.40f, 0.32f, 0.20f);

using Paint = std::function<Eigen::Vector3f(const Eigen::Vector2d&)>;
Paint Plain(const Eigen::Vector3f& color) {
  return [color](const Eigen::Vector2d&) { return color; };
}
Paint Mottled(const Eigen::Vector3f& color, double scale, float amount, uint32_t salt) {
  return [=](const Eigen::Vector2d& p) { return mapmesh::Mottle(color, p, scale, amount, salt); };
}
const Paint& AsphaltPaint() {
  static const Paint paint = Mottled(kAsphalt, 3.0, 0.3f, 11);
  return paint;
}

// Snapped to 1/1024 m, so that neighbouring tiles computing the same point on
// their common side from different pieces agree to the bit: no hairline cracks.
Eigen::Vector3f Snapped(const Eigen::Vector2d& p, float z) {
  const auto snap = [](double v) { return static_cast<float>(std::round(v * 1024.0) / 1024.0); };
  return {snap(p.x()), snap(p.y()), z};
}

// The point of `piece` at arc length s, `lateral` metres to its left.
Eigen::Vector3f At(const Piece& piece, double s, double lateral, float z) {
  const double heading = piece.HeadingAt(s);
  return Snapped(piece.PointAt(s) + lateral * Eigen::Vector2d(-std::sin(heading), std::cos(heading)), z);
}

// How many quads along [s0, s1] of `piece`: enough that arcs look round and
// that no two rows are more than `max_spacing` apart.
int Rows(const Piece& piece, double s0, double s1, double max_spacing) {
  double rows = (s1 - s0) / max_spacing;
  if (piece.curvature != 0.0) {
    const double radius = 1.0 / std::abs(piece.curvature) + kFarEdge;
    const double max_angle = 2.0 * std::acos(1.0 - kMaxSagitta / radius);
    rows = std::max(rows, std::abs(piece.curvature) * (s1 - s0) / max_angle);
  }
  return std::max(1, static_cast<int>(std::ceil(rows - 1e-9)));
}

// A flat band facing up between lateral offsets right < left over [s0, s1].
// Rows share vertices, so per-vertex colours blend along the band.
void AppendStrip(Mesh& mesh, const Piece& piece, double s0, double s1, double right, double left, float z,
                 const Paint& paint, double max_spacing = kMaxRowSpacing) {
  const int rows = Rows(piece, s0, s1, max_spacing);
  const Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
  uint32_t previous = 0;
  for (int i = 0; i <= rows; ++i) {
    const double s = s0 + (s1 - s0) * i / rows;
    const Eigen::Vector3f r = At(piece, s, right, z), l = At(piece, s, left, z);
    const uint32_t first = AddVertex(mesh, r, up, paint(r.head<2>().cast<double>()));
    AddVertex(mesh, l, up, paint(l.head<2>().cast<double>()));
    if (i > 0) {  // forward then leftward: counter-clockwise seen from above
      AddTriangle(mesh, previous, first, first + 1);
      AddTriangle(mesh, previous, first + 1, previous + 1);
    }
    previous = first;
  }
}

// The curb's face at `lateral`, from z0 up to z1, facing left (the road).
void AppendCurb(Mesh& mesh, const Piece& piece, double lateral, float z0, float z1) {
  const int rows = Rows(piece, 0.0, piece.length, piece.length);
  for (int i = 0; i < rows; ++i) {
    const double a = piece.length * i / rows, b = piece.length * (i + 1) / rows;
    mapmesh::AddFlatQuad(
        mesh,
        {At(piece, a, lateral, z0), At(piece, a, lateral, z1), At(piece, b, lateral, z1), At(piece, b, lateral, z0)},
        kCurbStone);
  }
}

void AppendDashes(Mesh& mesh, const Piece& piece, double lateral, const Eigen::Vector3f& color) {
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kLaneMarking);
  const int periods = std::max(1, static_cast<int>(std::lround(piece.length / kDashPeriod)));
  const double period = piece.length / periods;
  for (int k = 0; k < periods; ++k) {
    const double start = (k + 0.25) * period;  // half a gap at each end, a whole gap across tile sides
    AppendStrip(mesh, piece, start, start + period / 2, lateral - kLineWidth / 2, lateral + kLineWidth / 2,
                kMarkingHeight, Plain(color), period);
  }
}

// Asphalt and centre line of a straight or a curve, from one of its lanes.
void AppendCarriageway(Mesh& mesh, const Piece& lane, const Eigen::Vector3f& centre_line) {
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kRoad);
  AppendStrip(mesh, lane, 0.0, lane.length, kLaneEdge, kRoadCentre, kAsphaltHeight, AsphaltPaint());
  AppendStrip(mesh, lane, 0.0, lane.length, kRoadCentre, kFarEdge, kAsphaltHeight, AsphaltPaint());
  AppendDashes(mesh, lane, kRoadCentre, centre_line);
}

// The border of the asphalt along a lane's right edge: edge line, and a
// sidewalk with its curb (urban) or a gravel shoulder (desert) outside it.
void AppendRoadEdge(Mesh& mesh, const map::LaneCurve& lane, bool urban) {
  for (const Piece& piece : lane.pieces()) {
    mesh.semantic = static_cast<uint32_t>(SemanticClass::kLaneMarking);
    AppendStrip(mesh, piece, 0.0, piece.length, kLaneEdge + kEdgeLineInset, kLaneEdge + kEdgeLineInset + kLineWidth,
                kMarkingHeight, Plain(kWhitePaint), piece.length);
    // Inside a right turn the verge cannot reach past the bend's centre
    // (small tiles: the inner edge's radius is tile_size / 2 - 4 m).
    const double room = piece.curvature < 0.0 ? -1.0 / piece.curvature + kLaneEdge : kSidewalkWidth;
    if (urban) {  // the curb belongs to the sidewalk, as in Cityscapes
      mesh.semantic = static_cast<uint32_t>(SemanticClass::kSidewalk);
      AppendStrip(mesh, piece, 0.0, piece.length, kLaneEdge - std::min(kSidewalkWidth, room), kLaneEdge,
                  kSidewalkHeight, Mottled(kPavement, 1.5, 0.2f, 12));
      AppendCurb(mesh, piece, kLaneEdge, kAsphaltHeight, kSidewalkHeight);
    } else {
      mesh.semantic = static_cast<uint32_t>(SemanticClass::kTerrain);  // a gravel shoulder
      AppendStrip(mesh, piece, 0.0, piece.length, kLaneEdge - std::min(kShoulderWidth, room), kLaneEdge,
                  kShoulderHeight, Mottled(kGravel, 2.0, 0.2f, 13));
    }
  }
}

// A T-junction or crossroads fills its tile with asphalt, bounded by the
// lanes' outer edges (the right-turn arcs' fillets, the straight past a T's
// closed side) and the tile sides where arms leave. The region is
// star-shaped about the tile centre (every fillet is a circle about a tile
// corner with radius below half the tile), so a fan from the centre covers it.
void AppendJunctionSurface(Mesh& mesh, const std::vector<const LaneSegment*>& edges, EdgeMask mask,
                           const Eigen::Vector2d& centre, double half) {
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kRoad);
  const uint32_t hub =
      AddVertex(mesh, Snapped(centre, kAsphaltHeight), Eigen::Vector3f::UnitZ(), AsphaltPaint()(centre));
  // Boundary points in order with the asphalt on their left, so each
  // triangle (hub, a, b) is counter-clockwise seen from above.
  const auto fan = [&](const std::vector<Eigen::Vector3f>& boundary) {
    uint32_t previous = 0;
    for (std::size_t i = 0; i < boundary.size(); ++i) {
      const uint32_t current =
          AddVertex(mesh, boundary[i], Eigen::Vector3f::UnitZ(), AsphaltPaint()(boundary[i].head<2>().cast<double>()));
      if (i > 0) AddTriangle(mesh, hub, previous, current);
      previous = current;
    }
  };
  for (const LaneSegment* edge : edges) {
    for (const Piece& piece : edge->curve.pieces()) {
      std::vector<Eigen::Vector3f> boundary;
      const int rows = Rows(piece, 0.0, piece.length, kMaxRowSpacing);
      for (int i = 0; i <= rows; ++i) boundary.push_back(At(piece, piece.length * i / rows, kLaneEdge, kAsphaltHeight));
      fan(boundary);
    }
  }
  for (map::Edge side : map::kEdges) {
    if (!map::Has(mask, side)) continue;
    const Eigen::Vector2d out = map::Outward(side), along(-out.y(), out.x());  // along the side, asphalt to its left
    std::vector<Eigen::Vector3f> opening;
    for (double t : {-map::kLaneWidth, 0.0, map::kLaneWidth}) {
      opening.push_back(Snapped(centre + half * out + t * along, kAsphaltHeight));
    }
    fan(opening);
  }
}

// Zebra stripes across every arm, just inside the tile side. They stop
// short of the crossing road, so in small tiles they get shorter (and
// vanish below a metre) rather than overlap the next arm's crosswalk.
void AppendCrosswalks(Mesh& mesh, EdgeMask mask, const Eigen::Vector2d& centre, double half) {
  const double length = std::min(kCrosswalkLength, half - kCrosswalkFromSide - map::kLaneWidth - kCrosswalkEdgeClear);
  if (length < 1.0) return;
  mesh.semantic = static_cast<uint32_t>(SemanticClass::kCrosswalk);
  const double usable = 2 * map::kLaneWidth - 2 * kCrosswalkEdgeClear;
  const int stripes = static_cast<int>((usable + kCrosswalkStripe) / (2 * kCrosswalkStripe));
  for (map::Edge side : map::kEdges) {
    if (!map::Has(mask, side)) continue;
    const Eigen::Vector2d out = map::Outward(side);
    const Piece across{centre + (half - kCrosswalkFromSide - length) * out, std::atan2(out.y(), out.x()), length, 0.0};
    for (int k = 0; k < stripes; ++k) {
      const double middle = (k - (stripes - 1) / 2.0) * 2 * kCrosswalkStripe;
      AppendStrip(mesh, across, 0.0, length, middle - kCrosswalkStripe / 2, middle + kCrosswalkStripe / 2,
                  kMarkingHeight, Plain(kWhitePaint), length);
    }
  }
}

int Rank(map::Turn turn) {
  switch (turn) {
    case map::Turn::kRight:
      return 0;
    case map::Turn::kStraight:
      return 1;
    case map::Turn::kLeft:
      return 2;
    case map::Turn::kUTurn:
      return 3;
  }
  return 3;
}

// A lane's right edge is the road's edge unless the tile has an exit further
// right than the lane takes: no other lane then lies between it and the verge.
bool IsRoadEdge(const LaneSegment& lane, EdgeMask mask) {
  for (map::Edge exit : map::kEdges) {
    if (exit != lane.entry && map::Has(mask, exit) && Rank(map::TurnOf(lane.entry, exit)) < Rank(lane.turn)) {
      return false;
    }
  }
  return true;
}

}  // namespace

void AppendRoadTile(Mesh& mesh, const map::Map& map, const map::RoadGraph& graph, map::TileCoord tile) {
  const EdgeMask mask = map.ConnectionsAt(tile);
  SIM4CV_THROW_UNLESS(mask != 0, "tile " << tile.col << "," << tile.row << " holds no road");
  std::vector<const LaneSegment*> lanes;
  for (map::Edge entry : map::kEdges) {
    for (map::Edge exit : map::kEdges) {
      if (const auto id = graph.Find(tile, entry, exit)) lanes.push_back(&graph.segment(*id));
    }
  }
  SIM4CV_DEMAND(!lanes.empty());
  const bool urban = map.surroundings == map::Surroundings::kUrban;
  const map::TileKind kind = map::KindOf(mask);
  const Eigen::Vector2d centre = map.TileCentre(tile);
  if (kind == map::TileKind::kTJunction || kind == map::TileKind::kCrossroads) {
    std::vector<const LaneSegment*> edges;
    std::copy_if(lanes.begin(), lanes.end(), std::back_inserter(edges),
                 [&](const LaneSegment* lane) { return IsRoadEdge(*lane, mask); });
    AppendJunctionSurface(mesh, edges, mask, centre, map.tile_size / 2);
    if (urban) AppendCrosswalks(mesh, mask, centre, map.tile_size / 2);
  } else {
    const std::vector<Piece>& pieces = lanes.front()->curve.pieces();
    AppendCarriageway(mesh, pieces.front(), urban ? kWhitePaint : kYellowPaint);
    // A dead end's lane turns back on a half circle of 2 m about the tile
    // centre; the 4 m wide band about it is the turning circle's cap.
    if (kind == map::TileKind::kDeadEnd) {
      mesh.semantic = static_cast<uint32_t>(SemanticClass::kRoad);
      AppendStrip(mesh, pieces.at(1), 0.0, pieces.at(1).length, kLaneEdge, -kLaneEdge, kAsphaltHeight, AsphaltPaint());
    }
  }
  for (const LaneSegment* lane : lanes) {
    if (IsRoadEdge(*lane, mask)) AppendRoadEdge(mesh, lane->curve, urban);
  }
}

}  // namespace sim4cv::render
