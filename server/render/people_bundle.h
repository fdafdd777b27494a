// The packaged people walkers are drawn with (docs/assets.md): meshes that
// assets/build_assets.py converted at build time from Debian's
// sweethome3d-furniture and compiled into the daemon, so nothing is read
// from disk at run time. Each is in metres, z up, facing +x, its feet on
// z = 0 around the origin, 1.74 m tall (1 cm under kPedestrianHeight: room
// for the sway, walker_looks.h), coloured from its
// textures, labelled SemanticClass::kPerson.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "server/render/render_types.h"

namespace sim4cv::render {

// One person at two levels of detail: about 2,000 triangles, and about 700
// for when it is small on screen (DrawItem::far_mesh).
struct Person {
  Mesh full, far;
};

// The bundle's people, parsed once on first use. Empty when the build had no
// sweethome3d-furniture (CMake warned; walkers are then procedural).
const std::vector<Person>& PeopleMeshes();

// Parses a bundle (layout in assets/build_assets.py); throws naming what is
// wrong if `bytes` is not a whole, consistent bundle.
std::vector<Person> ParsePeopleBundle(std::span<const unsigned char> bytes);

}  // namespace sim4cv::render
