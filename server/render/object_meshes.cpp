#include "server/render/object_meshes.h"

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <numbers>

#include "protocol/semantic_classes.h"
#include "server/render/map_mesh_util.h"
#include "server/render/mesh_builder.h"

namespace sim4cv::render {
namespace {

using Eigen::Vector3f;
using map::ObjectKind;

using mapmesh::AddBox;

// Picks one entry of a palette, the same one for the same variant.
template <std::size_t N>
const Vector3f& Pick(const std::array<Vector3f, N>& palette, uint32_t variant, uint32_t salt) {
  return mapmesh::Pick(palette, variant, 0, salt);
}

// A box of walls and a gabled roof along the long (x) axis, all inside the
// footprint and exactly as tall as ShapeOf.
Mesh MakeHouse(uint32_t variant) {
  static const std::array<Vector3f, 6> kWalls = {Vector3f(0.75f, 0.66f, 0.50f), Vector3f(0.56f, 0.56f, 0.55f),
                                                 Vector3f(0.70f, 0.48f, 0.24f), Vector3f(0.48f, 0.53f, 0.60f),
                                                 Vector3f(0.50f, 0.22f, 0.14f), Vector3f(0.80f, 0.78f, 0.72f)};
  static const std::array<Vector3f, 4> kRoofs = {Vector3f(0.40f, 0.10f, 0.05f), Vector3f(0.11f, 0.11f, 0.12f),
                                                 Vector3f(0.22f, 0.12f, 0.07f), Vector3f(0.10f, 0.13f, 0.19f)};
  const Vector3f& wall = Pick(kWalls, variant, 1);
  const Vector3f& roof = Pick(kRoofs, variant, 2);
  const map::ObjectShape& shape = map::ShapeOf(ObjectKind::kHouse);
  const auto hx = static_cast<float>(shape.half_x), hy = static_cast<float>(shape.half_y);
  const auto top = static_cast<float>(shape.height);
  const float eaves = top - 1.6f;
  // Windows, doors and floors are drawn by the RGB shader (shading.h,
  // Facade), so the walls are one box, 5 cm inside the footprint.
  const float inset = 0.05f;
  Mesh mesh;
  AddBox(mesh, {0, 0, eaves / 2}, {hx - inset, hy - inset, eaves / 2}, wall);
  mapmesh::AddFlatQuad(
      mesh, {Vector3f(-hx, -hy, eaves), Vector3f(hx, -hy, eaves), Vector3f(hx, 0, top), Vector3f(-hx, 0, top)}, roof);
  mapmesh::AddFlatQuad(
      mesh, {Vector3f(hx, hy, eaves), Vector3f(-hx, hy, eaves), Vector3f(-hx, 0, top), Vector3f(hx, 0, top)}, roof);
  const float gable_x = hx - inset, gable_y = hy - inset;
  mapmesh::AddFlatTriangle(
      mesh, {Vector3f(gable_x, -gable_y, eaves), Vector3f(gable_x, gable_y, eaves), Vector3f(gable_x, 0, top)}, wall);
  mapmesh::AddFlatTriangle(
      mesh, {Vector3f(-gable_x, gable_y, eaves), Vector3f(-gable_x, -gable_y, eaves), Vector3f(-gable_x, 0, top)},
      wall);
  return mesh;
}

// A square trunk and a low-poly crown: two octagons (the lower one the
// crown's full radius) joined as an antiprism and closed by a cone above and
// below. Lower faces are darker, as under real foliage.
Mesh MakeTree(uint32_t variant, bool desert) {
  const map::ObjectShape& shape = map::ShapeOf(ObjectKind::kTree);
  const Vector3f bark(0.16f, 0.09f, 0.04f);
  // Desert trees are dusty olive, town trees a fuller green.
  const Vector3f leaves = (desert ? Vector3f(0.20f, 0.22f, 0.07f) : Vector3f(0.06f, 0.20f, 0.04f)) *
                          (0.85f + 0.3f * mapmesh::Hash01(variant, 0, 3));
  const auto top = static_cast<float>(shape.height);
  const auto radius = static_cast<float>(shape.crown_radius);
  Mesh mesh;
  AddBox(mesh, {0, 0, 1.5f}, {static_cast<float>(shape.half_x), static_cast<float>(shape.half_y), 1.5f}, bark);
  constexpr int kSides = 8;
  const Vector3f bottom(0, 0, 0.25f * top), apex(0, 0, top);
  std::array<Vector3f, kSides> lower, upper;
  for (int i = 0; i < kSides; ++i) {
    const float angle = 2.0f * std::numbers::pi_v<float> * static_cast<float>(i) / kSides;
    const float half_step = std::numbers::pi_v<float> / kSides;
    lower[i] = Vector3f(radius * std::cos(angle), radius * std::sin(angle), 0.51f * top);
    upper[i] = Vector3f(0.72f * radius * std::cos(angle + half_step), 0.72f * radius * std::sin(angle + half_step),
                        0.77f * top);
  }
  for (int i = 0; i < kSides; ++i) {
    const int next = (i + 1) % kSides;
    const float shade = (i % 2 == 0) ? 0.95f : 1.05f;
    mapmesh::AddFlatTriangle(mesh, {bottom, lower[next], lower[i]}, leaves * 0.7f);
    mapmesh::AddFlatTriangle(mesh, {lower[i], lower[next], upper[i]}, leaves * shade);
    mapmesh::AddFlatTriangle(mesh, {upper[i], lower[next], upper[next]}, leaves * (2.0f - shade));
    mapmesh::AddFlatTriangle(mesh, {upper[i], upper[next], apex}, (leaves * 1.15f).cwiseMin(1.0f));
  }
  return mesh;
}

// A pole on a base sleeve as wide as the footprint, with an arm reaching
// over the road (the object's +y: the generator turns lanterns to face
// along the lane beside them, the road on their left) and a lamp head.
Mesh MakeLantern() {
  const map::ObjectShape& shape = map::ShapeOf(ObjectKind::kLantern);
  const Vector3f metal(0.08f, 0.09f, 0.09f), lamp(0.95f, 0.85f, 0.55f);
  const auto top = static_cast<float>(shape.height);
  Mesh mesh;
  AddBox(mesh, {0, 0, 0.4f}, {static_cast<float>(shape.half_x), static_cast<float>(shape.half_y), 0.4f}, metal);
  AddBox(mesh, {0, 0, (top - 0.1f) / 2}, {0.08f, 0.08f, (top - 0.1f) / 2}, metal);
  AddBox(mesh, {0, 0.5f, top - 0.12f}, {0.05f, 0.45f, 0.05f}, metal);  // ends inside the head: no shared faces
  const std::size_t head = mesh.vertices.size();
  AddBox(mesh, {0, 1.1f, top - 0.1f}, {0.15f, 0.3f, 0.1f}, lamp);
  MarkEmissive(mesh, head);  // glows at night (its light: LanternLightOffset)
  return mesh;
}

// A raised lawn crossed by two gravel paths, and two benches by the paths.
Mesh MakePark(uint32_t variant) {
  const map::ObjectShape& shape = map::ShapeOf(ObjectKind::kPark);
  const Vector3f lawn(0.08f, 0.30f, 0.04f), gravel(0.45f, 0.38f, 0.26f);
  const Vector3f wood(0.30f, 0.15f, 0.05f), iron(0.06f, 0.06f, 0.06f);
  const auto half = static_cast<float>(shape.half_x), z = static_cast<float>(shape.height);
  const float path = 0.8f;  // half width
  Mesh mesh;
  // Pieces that tile the square without overlapping, so nothing fights.
  const auto patch = [&](float x0, float y0, float x1, float y1, const Vector3f& color, float mottle) {
    const uint32_t first = static_cast<uint32_t>(mesh.vertices.size());
    for (const auto& [x, y] : {std::pair{x0, y0}, std::pair{x1, y0}, std::pair{x1, y1}, std::pair{x0, y1}}) {
      mapmesh::AddVertex(mesh, {x, y, z}, Vector3f::UnitZ(),
                         mapmesh::Mottle(color, Eigen::Vector2d(x, y), 4.0, mottle, variant));
    }
    mapmesh::AddTriangle(mesh, first, first + 1, first + 2);
    mapmesh::AddTriangle(mesh, first, first + 2, first + 3);
  };
  for (float sx : {-1.0f, 1.0f}) {
    for (float sy : {-1.0f, 1.0f}) {
      patch(std::min(sx * path, sx * half), std::min(sy * path, sy * half), std::max(sx * path, sx * half),
            std::max(sy * path, sy * half), lawn, 0.25f);
    }
  }
  patch(-half, -path, half, path, gravel, 0.1f);
  patch(-path, path, path, half, gravel, 0.1f);
  patch(-path, -half, path, -path, gravel, 0.1f);
  // Each bench faces the east-west path: its back on the side away from it.
  for (float side : {-1.0f, 1.0f}) {
    const Vector3f at(side * 4.0f, side * 1.6f, 0.0f);
    AddBox(mesh, at + Vector3f(0, 0, 0.21f), {0.7f, 0.15f, 0.21f}, iron);
    AddBox(mesh, at + Vector3f(0, 0, 0.46f), {0.8f, 0.22f, 0.04f}, wood);
    AddBox(mesh, at + Vector3f(0, side * 0.2f, 0.75f), {0.8f, 0.03f, 0.22f}, wood);
  }
  return mesh;
}

// A road barrier: a red and white board on two uprights, each standing on
// a foot as deep as the footprint (which is what keeps it from tipping).
Mesh MakeObstacle() {
  const map::ObjectShape& shape = map::ShapeOf(ObjectKind::kObstacle);
  const Vector3f red(0.70f, 0.04f, 0.03f), white(0.80f, 0.80f, 0.78f), steel(0.25f, 0.25f, 0.27f);
  const auto hx = static_cast<float>(shape.half_x), hy = static_cast<float>(shape.half_y);
  const auto top = static_cast<float>(shape.height);
  const float post = 0.06f;  // half width of an upright and its foot
  Mesh mesh;
  for (float side : {-1.0f, 1.0f}) {
    const float x = side * (hx - post);
    AddBox(mesh, {x, 0, 0.04f}, {post, hy, 0.04f}, steel);
    AddBox(mesh, {x, 0, top / 2}, {post, post, top / 2}, steel);
  }
  constexpr int kStripes = 5;
  const float stripe = (2 * hx - 4 * post) / kStripes;  // between the uprights
  for (int i = 0; i < kStripes; ++i) {
    AddBox(mesh, {-hx + 2 * post + (i + 0.5f) * stripe, 0, top - 0.3f}, {stripe / 2, 0.03f, 0.22f},
           i % 2 == 0 ? red : white);
  }
  return mesh;
}

}  // namespace

// Each object is one class; a park is labelled terrain (its lawn and paths;
// its two benches are too small to matter), as Cityscapes labels grass.
Mesh MakeObjectMesh(map::ObjectKind kind, map::Surroundings surroundings, uint32_t variant) {
  switch (kind) {
    case ObjectKind::kHouse:
      return Labelled(MakeHouse(variant), SemanticClass::kBuilding);
    case ObjectKind::kTree:
      return Labelled(MakeTree(variant, surroundings == map::Surroundings::kDesert), SemanticClass::kVegetation);
    case ObjectKind::kLantern:
      return Labelled(MakeLantern(), SemanticClass::kPole);
    case ObjectKind::kPark:
      return Labelled(MakePark(variant), SemanticClass::kTerrain);
    case ObjectKind::kObstacle:
      return Labelled(MakeObstacle(), SemanticClass::kObstacle);
  }
  return {};
}

Vector3f LanternLightOffset() {
  return {0.0f, 1.1f, static_cast<float>(map::ShapeOf(ObjectKind::kLantern).height) - 0.25f};
}

}  // namespace sim4cv::render
