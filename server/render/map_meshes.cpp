#include "server/render/map_meshes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "protocol/semantic_classes.h"
#include "server/common/check.h"
#include "server/render/map_mesh_util.h"
#include "server/render/object_meshes.h"
#include "server/render/road_meshes.h"
#include "sim4cv.pb.h"

namespace sim4cv::render {
namespace {

constexpr double kGroundCell = 10.0;    // m, about: the ground's colour varies from vertex to vertex
constexpr int kCellsPerChunk = 6;       // ground cells along a chunk's side
constexpr double kMinMargin = 40.0;     // m of ground beyond the grid (at least two tiles)
constexpr double kSkirtReach = 2000.0;  // m from the origin: past any camera's far plane
// The skirt lies just under the ground and reaches a metre under its edge,
// so there is no seam between them and they never fight.
constexpr float kSkirtHeight = -0.05f;
constexpr double kSkirtOverlap = 1.0;

// Sand with long dunes (bands across a prevailing wind that wander a
// little) or lawn with lush and dry patches; finer mottling on both.
Eigen::Vector3f GroundColor(map::Surroundings surroundings, const Eigen::Vector2d& p) {
  if (surroundings == map::Surroundings::kDesert) {
    const Eigen::Vector3f sand(0.62f, 0.45f, 0.24f);
    const double across = 0.8 * p.x() + 0.6 * p.y() + 12.0 * mapmesh::Noise(p, 70.0, 21);
    const auto dune = static_cast<float>(0.5 + 0.5 * std::sin(2.0 * std::numbers::pi * across / 45.0));
    return mapmesh::Mottle(sand * (0.80f + 0.3f * dune), p, 12.0, 0.06f, 22);
  }
  const Eigen::Vector3f lush(0.08f, 0.21f, 0.04f), dry(0.22f, 0.25f, 0.08f);
  const float dryness = mapmesh::Noise(p, 30.0, 23);
  return mapmesh::Mottle(lush + (dry - lush) * (dryness * dryness), p, 7.0, 0.12f, 24);
}

// The ground's vertex lattice. Every chunk computes a lattice point the same
// way, so points on a chunk border are bit-identical on both sides.
struct GroundGrid {
  Eigen::Vector2d origin, cell;
  int columns = 0, rows = 0;

  Eigen::Vector2d Point(int i, int j) const { return origin + Eigen::Vector2d(i * cell.x(), j * cell.y()); }
  int ColumnOf(double x) const {
    return std::clamp(static_cast<int>(std::floor((x - origin.x()) / cell.x())), 0, columns - 1);
  }
  int RowOf(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - origin.y()) / cell.y())), 0, rows - 1);
  }
};

GroundGrid MakeGroundGrid(const map::Map& map) {
  const Eigen::Vector2d half = map.HalfExtent().array() + std::max(kMinMargin, 2 * map.tile_size);
  GroundGrid grid;
  grid.columns = static_cast<int>(std::ceil(2 * half.x() / kGroundCell));
  grid.rows = static_cast<int>(std::ceil(2 * half.y() / kGroundCell));
  grid.origin = -half;
  grid.cell = Eigen::Vector2d(2 * half.x() / grid.columns, 2 * half.y() / grid.rows);
  return grid;
}

// Lattice cells [i0, i1) x [j0, j1) as one sheet with shared vertices, so the
// colour blends smoothly from vertex to vertex.
void AppendGround(Mesh& mesh, const GroundGrid& grid, int i0, int i1, int j0, int j1, map::Surroundings surroundings) {
  const auto first = static_cast<uint32_t>(mesh.vertices.size());
  const int width = i1 - i0 + 1;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const Eigen::Vector2d p = grid.Point(i, j);
      mapmesh::AddVertex(mesh, Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), 0.0f),
                         Eigen::Vector3f::UnitZ(), GroundColor(surroundings, p));
    }
  }
  for (int j = 0; j < j1 - j0; ++j) {
    for (int i = 0; i < i1 - i0; ++i) {
      const auto corner = first + static_cast<uint32_t>(j * width + i);
      const auto above = corner + static_cast<uint32_t>(width);
      mapmesh::AddTriangle(mesh, corner, corner + 1, above + 1);
      mapmesh::AddTriangle(mesh, corner, above + 1, above);
    }
  }
}

// A flat square ring from just inside the ground's edge out to kSkirtReach.
Mesh MakeSkirt(const GroundGrid& grid, map::Surroundings surroundings) {
  const Eigen::Vector2d inner_low = grid.origin.array() + kSkirtOverlap;
  const Eigen::Vector2d inner_high = grid.Point(grid.columns, grid.rows).array() - kSkirtOverlap;
  const std::array<Eigen::Vector2d, 4> inner = {inner_low, Eigen::Vector2d(inner_high.x(), inner_low.y()), inner_high,
                                                Eigen::Vector2d(inner_low.x(), inner_high.y())};
  const std::array<Eigen::Vector2d, 4> outer = {
      Eigen::Vector2d(-kSkirtReach, -kSkirtReach), Eigen::Vector2d(kSkirtReach, -kSkirtReach),
      Eigen::Vector2d(kSkirtReach, kSkirtReach), Eigen::Vector2d(-kSkirtReach, kSkirtReach)};
  Mesh mesh;
  const auto vertex = [&](const Eigen::Vector2d& p) {
    return mapmesh::AddVertex(mesh, Eigen::Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), kSkirtHeight),
                              Eigen::Vector3f::UnitZ(), GroundColor(surroundings, p));
  };
  for (int k = 0; k < 4; ++k) {
    // inner k, outer k, outer k+1, inner k+1: counter-clockwise seen from above.
    const uint32_t a = vertex(inner[k]), b = vertex(outer[k]), c = vertex(outer[(k + 1) % 4]),
                   d = vertex(inner[(k + 1) % 4]);
    mapmesh::AddTriangle(mesh, a, b, c);
    mapmesh::AddTriangle(mesh, a, c, d);
  }
  return mesh;
}

uint32_t ClassOf(map::ObjectKind kind) {
  switch (kind) {
    case map::ObjectKind::kHouse:
      return proto::OBJECT_CLASS_BUILDING;
    case map::ObjectKind::kTree:
      return proto::OBJECT_CLASS_TREE;
    case map::ObjectKind::kLantern:
      return proto::OBJECT_CLASS_LANTERN;
    case map::ObjectKind::kPark:
      return proto::OBJECT_CLASS_PARK;
    case map::ObjectKind::kObstacle:
      return proto::OBJECT_CLASS_OBSTACLE;
  }
  return proto::OBJECT_CLASS_UNSPECIFIED;
}

Eigen::Matrix4f ObjectPose(const map::MapObject& object) {
  Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
  const auto yaw = static_cast<float>(object.rotation_deg * std::numbers::pi / 180.0);
  pose.topLeftCorner<3, 3>() = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  pose.block<3, 1>(0, 3) =
      Eigen::Vector3f(static_cast<float>(object.position.x()), static_cast<float>(object.position.y()), 0.0f);
  return pose;
}

}  // namespace

std::vector<MapDrawable> BuildMapDrawables(const map::Map& map, const map::RoadGraph& graph,
                                           InstanceId first_instance) {
  SIM4CV_THROW_UNLESS(first_instance != kUnlabelled &&
                          first_instance + map.objects.size() - 1 <= std::numeric_limits<InstanceId>::max(),
                      "instance ids " << first_instance << ".." << first_instance + map.objects.size() - 1
                                      << " of map '" << map.name << "' do not fit 1..65535");
  const GroundGrid grid = MakeGroundGrid(map);
  const int chunk_columns = (grid.columns + kCellsPerChunk - 1) / kCellsPerChunk;
  const int chunk_rows = (grid.rows + kCellsPerChunk - 1) / kCellsPerChunk;
  // The ground is terrain (grass or sand); road tiles set their parts' classes.
  std::vector<Mesh> chunks(static_cast<std::size_t>(chunk_columns) * chunk_rows,
                           Labelled(Mesh{}, SemanticClass::kTerrain));
  for (int row = 0; row < chunk_rows; ++row) {
    for (int column = 0; column < chunk_columns; ++column) {
      AppendGround(chunks[row * chunk_columns + column], grid, column * kCellsPerChunk,
                   std::min(grid.columns, (column + 1) * kCellsPerChunk), row * kCellsPerChunk,
                   std::min(grid.rows, (row + 1) * kCellsPerChunk), map.surroundings);
    }
  }
  // A road tile goes into the chunk holding its centre.
  for (std::size_t index = 0; index < map.road.size(); ++index) {
    if (map.road[index] == 0) continue;
    const map::TileCoord tile = map.CoordOf(index);
    const Eigen::Vector2d centre = map.TileCentre(tile);
    const int column = grid.ColumnOf(centre.x()) / kCellsPerChunk, row = grid.RowOf(centre.y()) / kCellsPerChunk;
    Mesh& chunk = chunks[row * chunk_columns + column];
    AppendRoadTile(chunk, map, graph, tile);
    chunk.semantic = static_cast<uint32_t>(SemanticClass::kTerrain);
  }

  std::vector<MapDrawable> drawables;
  drawables.reserve(chunks.size() + 1 + map.objects.size());
  for (Mesh& chunk : chunks) drawables.push_back({std::move(chunk), Eigen::Matrix4f::Identity(), kUnlabelled, 0});
  drawables.push_back(
      {Labelled(MakeSkirt(grid, map.surroundings), SemanticClass::kTerrain), Eigen::Matrix4f::Identity(), kUnlabelled, 0});
  for (std::size_t i = 0; i < map.objects.size(); ++i) {
    const map::MapObject& object = map.objects[i];
    drawables.push_back({MakeObjectMesh(object.kind, map.surroundings, static_cast<uint32_t>(i)), ObjectPose(object),
                         static_cast<InstanceId>(first_instance + i), ClassOf(object.kind)});
  }
  return drawables;
}

}  // namespace sim4cv::render
