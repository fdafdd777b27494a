// Small building blocks shared by the map's road, ground and object meshes:
// vertices and flat faces, and the noise that stands in for textures (the
// renderer has none, so surfaces get their grain from per-vertex colours).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "server/render/render_types.h"

namespace sim4cv::render::mapmesh {

// A pseudo-random value in [0, 1) for an integer pair: the same pair always
// gives the same value (no state, no order dependence).
float Hash01(int64_t x, int64_t y, uint32_t salt);

// Smooth value noise in [0, 1] with features about `scale` metres. A pure
// function of the position, so vertices that two pieces share (a tile side,
// a chunk border) get the same colour and no seam shows.
float Noise(const Eigen::Vector2d& p, double scale, uint32_t salt);

// `base` brightened or darkened by up to `amount` (a fraction) by Noise.
Eigen::Vector3f Mottle(const Eigen::Vector3f& base, const Eigen::Vector2d& p, double scale, float amount,
                       uint32_t salt);

uint32_t AddVertex(Mesh& mesh, const Eigen::Vector3f& position, const Eigen::Vector3f& normal,
                   const Eigen::Vector3f& color);
void AddTriangle(Mesh& mesh, uint32_t a, uint32_t b, uint32_t c);

// A flat-shaded triangle or quad with its own vertices (so its normal stays
// crisp); corners counter-clockwise seen from the front, the quad planar.
void AddFlatTriangle(Mesh& mesh, const std::array<Eigen::Vector3f, 3>& corners, const Eigen::Vector3f& color);
void AddFlatQuad(Mesh& mesh, const std::array<Eigen::Vector3f, 4>& corners, const Eigen::Vector3f& color);

// A box of `half_extents` centred on `centre` (axis-aligned in the mesh's
// frame), appended to `mesh`.
void AddBox(Mesh& mesh, const Eigen::Vector3f& centre, const Eigen::Vector3f& half_extents,
            const Eigen::Vector3f& color);

// One entry of a palette, the same one for the same (variant, stream, salt):
// `stream` keeps one family of models' choices apart from another's, `salt`
// one choice of a model (roof, walls, ...) apart from the next.
template <std::size_t N>
const Eigen::Vector3f& Pick(const std::array<Eigen::Vector3f, N>& palette, uint32_t variant, int64_t stream,
                            uint32_t salt) {
  return palette[static_cast<std::size_t>(Hash01(variant, stream, salt) * N) % N];
}


}  // namespace sim4cv::render::mapmesh
