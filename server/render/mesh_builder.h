// Procedural meshes for the built-in scenes: z-up world, metres, front faces
// counter-clockwise seen from outside, outward unit normals, flat shading
// (vertices are not shared between faces so the normals stay crisp).
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

#include "server/render/render_types.h"

namespace sim4cv::render {

// An axis-aligned box centred at the origin: 24 vertices, 12 triangles.
Mesh MakeBox(const Eigen::Vector3f& half_extents, const Eigen::Vector3f& color);

// A square at z = 0 spanning [-half_size, half_size]^2, split into an 8x8
// checkerboard of slightly different tints so motion over it is visible.
Mesh MakeGroundPlane(float half_size, const Eigen::Vector3f& color);

// A flat two-lane road (total width 2 * lane_width) just above z = 0 along the
// closed polyline (the last point joins the first; at least 3 points), with
// solid edge lines and a dashed centre line raised slightly above the asphalt.
Mesh MakeRoadLoop(const std::vector<Eigen::Vector2f>& closed_centerline, float lane_width,
                  const Eigen::Vector3f& asphalt, const Eigen::Vector3f& marking);

// Body styles of cars; every style fills the same bounds, so one physics box
// and one 3D box serve all of them (the truck is a light box truck: a cab
// and a white cargo box as tall as the bounds).
enum class CarStyle { kSedan, kHatchback, kEstate, kSuv, kVan, kPickup, kTruck };
inline constexpr int kCarStyleCount = 7;

// A car: wheels, painted body, glasshouse and roof, head- and tail-lamps,
// x forward. Its bounds are exactly [-length/2, length/2] x [-width/2,
// width/2] x [-height/2, height/2], so a physics box with those half
// extents matches it. 120 triangles.
Mesh MakeCarMesh(float length, float width, float height, const Eigen::Vector3f& color,
                 CarStyle style = CarStyle::kHatchback);

// A quadrotor of `span` (tip to tip along its diagonals), centred at the
// origin: the body (hub, two crossed arms, four motors) and one two-bladed
// rotor, whose origin is its hub. Each rotor turns inside the span.
struct UavParts {
  Mesh body, rotor;
};
UavParts MakeUavParts(float span, const Eigen::Vector3f& color);
// Where the four rotors' hubs are on the body.
std::array<Eigen::Vector3f, 4> RotorHubs(float span);
// The body-frame pose of rotor 0..3 at `sim_time` seconds: spinning about
// its hub, diagonal pairs in opposite directions.
Eigen::Matrix4f RotorPose(float span, std::size_t rotor, double sim_time);
// Body and rotors at rest in one mesh.
Mesh MakeUavMesh(float span, const Eigen::Vector3f& color);

// Appends `part` moved by `transform` (normals follow its inverse transpose;
// a mirroring transform keeps the faces counter-clockwise).
void AppendMesh(Mesh& into, const Mesh& part, const Eigen::Matrix4f& transform);

}  // namespace sim4cv::render
