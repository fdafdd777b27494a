#include "server/render/map_mesh_util.h"

#include <Eigen/Geometry>
#include <cmath>

#include "server/render/mesh_builder.h"

namespace sim4cv::render::mapmesh {
namespace {

float SmoothStep(float t) { return t * t * (3.0f - 2.0f * t); }

}  // namespace

// The finaliser of MurmurHash3 over the mixed pair: well spread, cheap.
float Hash01(int64_t x, int64_t y, uint32_t salt) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^ static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^
               (static_cast<uint64_t>(salt) << 32);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<float>(h >> 40) / static_cast<float>(1u << 24);
}

float Noise(const Eigen::Vector2d& p, double scale, uint32_t salt) {
  const double u = p.x() / scale, v = p.y() / scale;
  const double fu = std::floor(u), fv = std::floor(v);
  const auto x = static_cast<int64_t>(fu), y = static_cast<int64_t>(fv);
  const float tx = SmoothStep(static_cast<float>(u - fu)), ty = SmoothStep(static_cast<float>(v - fv));
  const float bottom = Hash01(x, y, salt) + tx * (Hash01(x + 1, y, salt) - Hash01(x, y, salt));
  const float top = Hash01(x, y + 1, salt) + tx * (Hash01(x + 1, y + 1, salt) - Hash01(x, y + 1, salt));
  return bottom + ty * (top - bottom);
}

Eigen::Vector3f Mottle(const Eigen::Vector3f& base, const Eigen::Vector2d& p, double scale, float amount,
                       uint32_t salt) {
  const float factor = 1.0f + amount * (2.0f * Noise(p, scale, salt) - 1.0f);
  return (base * factor).cwiseMin(1.0f);
}

uint32_t AddVertex(Mesh& mesh, const Eigen::Vector3f& position, const Eigen::Vector3f& normal,
                   const Eigen::Vector3f& color) {
  mesh.vertices.push_back({{position.x(), position.y(), position.z()},
                           {normal.x(), normal.y(), normal.z()},
                           {color.x(), color.y(), color.z()},
                           mesh.semantic});
  return static_cast<uint32_t>(mesh.vertices.size() - 1);
}

void AddTriangle(Mesh& mesh, uint32_t a, uint32_t b, uint32_t c) { mesh.indices.insert(mesh.indices.end(), {a, b, c}); }

void AddFlatTriangle(Mesh& mesh, const std::array<Eigen::Vector3f, 3>& corners, const Eigen::Vector3f& color) {
  const Eigen::Vector3f normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]).normalized();
  const uint32_t first = AddVertex(mesh, corners[0], normal, color);
  AddVertex(mesh, corners[1], normal, color);
  AddVertex(mesh, corners[2], normal, color);
  AddTriangle(mesh, first, first + 1, first + 2);
}

void AddFlatQuad(Mesh& mesh, const std::array<Eigen::Vector3f, 4>& corners, const Eigen::Vector3f& color) {
  const Eigen::Vector3f normal = (corners[1] - corners[0]).cross(corners[3] - corners[0]).normalized();
  const uint32_t first = AddVertex(mesh, corners[0], normal, color);
  for (int i = 1; i < 4; ++i) AddVertex(mesh, corners[i], normal, color);
  AddTriangle(mesh, first, first + 1, first + 2);
  AddTriangle(mesh, first, first + 2, first + 3);
}

void AddBox(Mesh& mesh, const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extents,
            const Eigen::Vector3f& color) {
  Eigen::Matrix4f at = Eigen::Matrix4f::Identity();
  at.block<3, 1>(0, 3) = centre;
  AppendMesh(mesh, MakeBox(half_extents, color), at);
}

}  // namespace sim4cv::render::mapmesh
