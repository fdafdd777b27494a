// Meshes for the traffic of server/sim/traffic: walkers, traffic lights and
// their lit lamps, and the colours of traffic cars (which are drawn with
// MakeCarMesh). Each model is in its own frame, z up, x forward, origin on
// the ground; the traffic state's pose (position, heading about z) places it.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "server/render/render_types.h"
#include "server/sim/traffic/signal.h"
#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::render {

// How tall a walker is, m.
inline constexpr float kPedestrianHeight = 1.75f;
// Half extents of the 3D box a walker's ground truth gives: front to back
// (room for a full stride, kMaxLimbSwing), shoulder to shoulder, head to toe.
inline const Eigen::Vector3d kPedestrianBox(0.5, 0.33, kPedestrianHeight / 2.0);
// Where a walker's limbs hang from, m: hips and shoulders (arm pivots), either side of x.
inline constexpr float kHipHeight = 0.89f, kHipY = 0.1f, kArmPivotHeight = 1.44f, kArmPivotY = 0.265f;
// A full gait cycle (two steps) covers this much ground, m.
inline constexpr double kStrideM = 1.4;
// The largest swing of a leg or an arm about its joint, radians (22 degrees).
inline constexpr double kMaxLimbSwing = 0.38;
// The traffic light's housing: its top, m above the pole's foot.
inline constexpr float kTrafficLightHeight = 3.1f;

// A walker's parts: the body (torso, head, hair) with its origin on the
// ground between the feet, facing +x; a leg (with its shoe) and an arm, each
// with its origin at the joint it hangs from. `variant` picks the clothes,
// skin and hair; the same variant always gives the same meshes.
struct PedestrianParts {
  Mesh body, leg, arm;
};
PedestrianParts MakePedestrianParts(uint32_t variant);

// The body-frame poses of the left leg, right leg, left arm and right arm
// (meshes PedestrianParts::leg, leg, arm, arm) at gait `phase` (radians) with
// limbs swinging up to `swing` radians (at most kMaxLimbSwing): the limbs stay
// inside kPedestrianBox whatever the phase.
std::array<Eigen::Matrix4f, 4> LimbPoses(double phase, double swing);
// The gait phase of a walker at `position` facing `heading` (radians from
// +x): one cycle per kStrideM along the heading. A function of the pose
// alone, so a replayed run (which logs poses) swings the same limbs.
double GaitPhase(const Eigen::Vector2d& position, double heading);
// How far the limbs swing at `speed` m/s: none standing, full at 1.4 m/s and up.
double LimbSwing(double speed);

// A walker's meshes once added to the scene's mesh list.
struct WalkerMeshIds {
  MeshId body = 0, leg = 0, arm = 0;
};
// Appends the four limbs of a walker whose body is drawn at `body_pose`,
// swinging for its ground `position`, `heading` and `speed` (instance `id`).
void AppendLimbs(std::vector<DrawItem>& items, const WalkerMeshIds& meshes, const Eigen::Matrix4f& body_pose,
                 const Eigen::Vector2d& position, double heading, double speed, InstanceId id);

// A walker standing, in one mesh: body and limbs at rest. 108 triangles.
Mesh MakePedestrianMesh(uint32_t variant);

// A traffic light: a pole and, near its top, a housing with three dark lamps
// (red on top, yellow, green below) under visors, facing +x. Origin at the
// pole's foot. Turned by TrafficPlan::Light::heading, +x looks back along the
// arm at the traffic coming in. 96 triangles.
Mesh MakeTrafficLightMesh();

// The lit lamp of `signal`: a bright square plate, centred on its origin,
// facing +x. Draw it each frame at LampOffset(signal) in the light's frame,
// where it sits 5 mm in front of that signal's dark lamp. 12 triangles.
Mesh MakeLampMesh(traffic::Signal signal);
Eigen::Vector3f LampOffset(traffic::Signal signal);

// Zebra markings of every crosswalk: white stripes along the road across
// both lanes, kCrosswalkHalfWidth either side of its middle, just above the
// asphalt (road_meshes.h's marking height). Flat, unlabelled, in world
// coordinates. 2 triangles a stripe.
Mesh MakeCrosswalkMarkings(const std::vector<traffic::TrafficPlan::Crosswalk>& crosswalks);

// The body colour of traffic car number `variant` (parked or moving): common
// car colours, neighbouring variants different, the target car's red and
// the UAV's blue left out so the simulated vehicles stand apart.
Eigen::Vector3f TrafficCarColour(uint32_t variant);

}  // namespace sim4cv::render
