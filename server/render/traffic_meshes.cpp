#include "server/render/traffic_meshes.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "protocol/semantic_classes.h"
#include "server/render/map_mesh_util.h"
#include "server/render/mesh_builder.h"
#include "server/render/road_meshes.h"

namespace sim4cv::render {
namespace {

using Eigen::Vector3f;
using traffic::Signal;

using mapmesh::AddBox;

// The same entry for the same variant; `salt` keeps the choices of one
// walker (shirt, trousers, ...) independent of each other.
template <std::size_t N>
const Vector3f& Pick(const std::array<Vector3f, N>& palette, uint32_t variant, uint32_t salt) {
  return mapmesh::Pick(palette, variant, 1, salt);
}

// The housing's front face (x) and its lamps' heights.
constexpr float kHousingFront = 0.15f;
constexpr float kLampHalf = 0.11f;   // the dark lamps' half side
constexpr float kLampDepth = 0.02f;  // how far the dark lamps stand out of the housing
constexpr float kHousingMiddle = 2.6f;
constexpr float kLampSpacing = 0.3f;

float LampHeight(Signal signal) {
  switch (signal) {
    case Signal::kRed:
      return kHousingMiddle + kLampSpacing;
    case Signal::kYellow:
      return kHousingMiddle;
    case Signal::kGreen:
      return kHousingMiddle - kLampSpacing;
  }
  return kHousingMiddle;
}

// Lit and dark colours of a lamp.
Vector3f LitColour(Signal signal) {
  switch (signal) {
    case Signal::kRed:
      return {1.0f, 0.12f, 0.06f};
    case Signal::kYellow:
      return {1.0f, 0.78f, 0.10f};
    case Signal::kGreen:
      return {0.15f, 1.0f, 0.40f};
  }
  return Vector3f::Ones();
}
Vector3f DarkColour(Signal signal) { return LitColour(signal) * 0.18f; }

}  // namespace

PedestrianParts MakePedestrianParts(uint32_t variant) {
  static const std::array<Vector3f, 8> kShirts = {Vector3f(0.70f, 0.12f, 0.10f), Vector3f(0.12f, 0.25f, 0.55f),
                                                  Vector3f(0.85f, 0.85f, 0.80f), Vector3f(0.15f, 0.40f, 0.20f),
                                                  Vector3f(0.85f, 0.65f, 0.15f), Vector3f(0.30f, 0.30f, 0.32f),
                                                  Vector3f(0.55f, 0.25f, 0.55f), Vector3f(0.20f, 0.55f, 0.65f)};
  static const std::array<Vector3f, 5> kTrousers = {Vector3f(0.10f, 0.12f, 0.25f), Vector3f(0.08f, 0.08f, 0.08f),
                                                    Vector3f(0.40f, 0.33f, 0.22f), Vector3f(0.30f, 0.30f, 0.30f),
                                                    Vector3f(0.20f, 0.28f, 0.45f)};
  static const std::array<Vector3f, 4> kSkins = {Vector3f(0.90f, 0.72f, 0.58f), Vector3f(0.72f, 0.52f, 0.38f),
                                                 Vector3f(0.48f, 0.32f, 0.22f), Vector3f(0.30f, 0.20f, 0.14f)};
  static const std::array<Vector3f, 4> kHair = {Vector3f(0.06f, 0.05f, 0.04f), Vector3f(0.30f, 0.18f, 0.08f),
                                                Vector3f(0.75f, 0.62f, 0.35f), Vector3f(0.55f, 0.55f, 0.55f)};
  const Vector3f shoes(0.05f, 0.05f, 0.06f);
  const Vector3f& shirt = Pick(kShirts, variant, 11);
  const Vector3f& trousers = Pick(kTrousers, variant, 12);
  const Vector3f& skin = Pick(kSkins, variant, 13);
  const Vector3f& hair = Pick(kHair, variant, 14);
  // Heights from the ground up; parts that meet overlap a little, so no
  // faces share a plane (z-fighting) and no gaps show. Limbs hang from
  // their joint (kHip*, kArmPivot*), the origin of their mesh.
  PedestrianParts parts;
  AddBox(parts.leg, {0.04f, 0.0f, 0.04f - kHipHeight}, {0.13f, 0.055f, 0.04f}, shoes);  // toes forward: the facing
  AddBox(parts.leg, {0.0f, 0.0f, 0.48f - kHipHeight}, {0.075f, 0.07f, 0.41f}, trousers);  // 0.07 .. 0.89 m
  AddBox(parts.arm, {0.0f, 0.0f, -0.31f}, {0.055f, 0.055f, 0.31f}, shirt);               // 0.82 .. 1.44 m
  AddBox(parts.body, {0.0f, 0.0f, 1.15f}, {0.12f, 0.2f, 0.29f}, shirt);                  // torso, 0.86 .. 1.44 m
  AddBox(parts.body, {0.0f, 0.0f, 1.55f}, {0.1f, 0.085f, 0.12f}, skin);  // head (and neck), 1.43 .. 1.67 m
  AddBox(parts.body, {-0.005f, 0.0f, 1.705f}, {0.105f, 0.09f, 0.045f}, hair);  // 1.66 .. kPedestrianHeight
  for (Mesh* part : {&parts.body, &parts.leg, &parts.arm}) *part = Labelled(std::move(*part), SemanticClass::kPerson);
  return parts;
}

std::array<Eigen::Matrix4f, 4> LimbPoses(double phase, double swing) {
  // Legs swing opposite each other, each arm opposite its own side's leg.
  const auto swing_about_y = [](float angle, float y, float height) {
    Eigen::Matrix4f pose = Eigen::Matrix4f::Identity();
    pose.topLeftCorner<3, 3>() = Eigen::AngleAxisf(angle, Vector3f::UnitY()).toRotationMatrix();
    pose.block<3, 1>(0, 3) = Vector3f(0.0f, y, height);
    return pose;
  };
  const auto angle = static_cast<float>(std::min(swing, kMaxLimbSwing) * std::sin(phase));
  return {swing_about_y(angle, kHipY, kHipHeight), swing_about_y(-angle, -kHipY, kHipHeight),
          swing_about_y(-angle, kArmPivotY, kArmPivotHeight), swing_about_y(angle, -kArmPivotY, kArmPivotHeight)};
}

double GaitPhase(const Eigen::Vector2d& position, double heading) {
  const double along = position.x() * std::cos(heading) + position.y() * std::sin(heading);
  return 2.0 * std::numbers::pi * along / kStrideM;
}

double LimbSwing(double speed) { return kMaxLimbSwing * std::clamp(speed / 1.4, 0.0, 1.0); }

void AppendLimbs(std::vector<DrawItem>& items, const WalkerMeshIds& meshes, const Eigen::Matrix4f& body_pose,
                 const Eigen::Vector2d& position, double heading, double speed, InstanceId id) {
  const std::array<Eigen::Matrix4f, 4> limbs = LimbPoses(GaitPhase(position, heading), LimbSwing(speed));
  for (std::size_t limb = 0; limb < limbs.size(); ++limb) {
    items.push_back({limb < 2 ? meshes.leg : meshes.arm, body_pose * limbs[limb], id});
  }
}

Mesh MakePedestrianMesh(uint32_t variant) {
  const PedestrianParts parts = MakePedestrianParts(variant);
  Mesh mesh = parts.body;
  const std::array<Eigen::Matrix4f, 4> limbs = LimbPoses(0.0, 0.0);
  for (std::size_t i = 0; i < limbs.size(); ++i) AppendMesh(mesh, i < 2 ? parts.leg : parts.arm, limbs[i]);
  return mesh;
}

Mesh MakeTrafficLightMesh() {
  const Vector3f metal(0.12f, 0.13f, 0.13f), housing(0.06f, 0.06f, 0.06f), visor(0.02f, 0.02f, 0.02f);
  Mesh mesh;
  AddBox(mesh, {0.0f, 0.0f, 1.25f}, {0.07f, 0.07f, 1.25f}, metal);  // up into the housing
  const float housing_half_height = kTrafficLightHeight - kHousingMiddle;
  AddBox(mesh, {0.0f, 0.0f, kHousingMiddle}, {kHousingFront, 0.18f, housing_half_height}, housing);
  for (Signal signal : {Signal::kRed, Signal::kYellow, Signal::kGreen}) {
    const float z = LampHeight(signal);
    AddBox(mesh, {kHousingFront + kLampDepth / 2, 0.0f, z}, {kLampDepth / 2, kLampHalf, kLampHalf}, DarkColour(signal));
    AddBox(mesh, {kHousingFront + 0.105f, 0.0f, z + kLampHalf + 0.02f}, {0.1f, 0.13f, 0.01f},
           visor);  // 5 mm off the face
  }
  return Labelled(std::move(mesh), SemanticClass::kTrafficLight);
}

Mesh MakeLampMesh(Signal signal) {
  return Labelled(MakeBox({0.005f, kLampHalf - 0.01f, kLampHalf - 0.01f}, LitColour(signal)),
                  SemanticClass::kTrafficLight);
}

Eigen::Vector3f LampOffset(Signal signal) {
  // The plate's back face 5 mm in front of the dark lamp's face.
  return {kHousingFront + kLampDepth + 0.005f + 0.005f, 0.0f, LampHeight(signal)};
}

Mesh MakeCrosswalkMarkings(const std::vector<traffic::TrafficPlan::Crosswalk>& crosswalks) {
  // Stripes 0.5 m wide, 1 m apart, across both 4 m lanes.
  constexpr double kStripeHalf = 0.25, kPitch = 1.0, kRoadHalf = map::kLaneWidth;
  const Vector3f white(0.92f, 0.92f, 0.90f);
  Mesh mesh;
  for (const traffic::TrafficPlan::Crosswalk& crosswalk : crosswalks) {
    for (double lateral = -kRoadHalf + kPitch / 2; lateral < kRoadHalf; lateral += kPitch) {
      const auto corner = [&](double across, double along) {
        const Eigen::Vector2d p = crosswalk.middle + crosswalk.across * across + crosswalk.along * along;
        return Vector3f(static_cast<float>(p.x()), static_cast<float>(p.y()), kMarkingHeight);
      };
      const double half = traffic::kCrosswalkHalfWidth;
      std::array<Vector3f, 4> quad = {corner(lateral - kStripeHalf, -half), corner(lateral + kStripeHalf, -half),
                                      corner(lateral + kStripeHalf, half), corner(lateral - kStripeHalf, half)};
      // Counter-clockwise seen from above, whichever way across/along turn.
      if ((quad[1] - quad[0]).cross(quad[2] - quad[0]).z() < 0) std::swap(quad[1], quad[3]);
      mapmesh::AddFlatQuad(mesh, quad, white);
    }
  }
  return Labelled(std::move(mesh), SemanticClass::kCrosswalk);
}

Eigen::Vector3f TrafficCarColour(uint32_t variant) {
  // Weighted like the colours of cars on European roads: mostly white,
  // black, grey and silver, a few coloured ones. Consecutive variants step
  // through the table by 7 (coprime to its 25 entries), so neighbours differ.
  static const std::array<Vector3f, 25> kColours = {
      Vector3f(0.85f, 0.85f, 0.83f), Vector3f(0.85f, 0.85f, 0.83f), Vector3f(0.85f, 0.85f, 0.83f),  // white
      Vector3f(0.92f, 0.92f, 0.90f), Vector3f(0.80f, 0.81f, 0.80f),                                  // white
      Vector3f(0.04f, 0.04f, 0.05f), Vector3f(0.05f, 0.05f, 0.06f), Vector3f(0.03f, 0.03f, 0.035f),  // black
      Vector3f(0.07f, 0.07f, 0.08f),                                                                 // black
      Vector3f(0.55f, 0.56f, 0.58f), Vector3f(0.60f, 0.61f, 0.62f), Vector3f(0.50f, 0.51f, 0.53f),  // silver
      Vector3f(0.58f, 0.58f, 0.56f),                                                                 // silver
      Vector3f(0.28f, 0.29f, 0.30f), Vector3f(0.22f, 0.23f, 0.25f), Vector3f(0.33f, 0.33f, 0.34f),  // grey
      Vector3f(0.26f, 0.26f, 0.26f),                                                                 // grey
      Vector3f(0.10f, 0.18f, 0.38f), Vector3f(0.30f, 0.45f, 0.60f),                                  // blues
      Vector3f(0.40f, 0.05f, 0.08f),                                                                 // maroon
      Vector3f(0.12f, 0.28f, 0.16f),                                                                 // dark green
      Vector3f(0.70f, 0.62f, 0.45f),                                                                 // beige
      Vector3f(0.88f, 0.70f, 0.10f),                                                                 // yellow
      Vector3f(0.35f, 0.20f, 0.12f),                                                                 // brown
      Vector3f(0.95f, 0.40f, 0.05f),                                                                 // orange
  };
  return kColours[(variant * 7u) % kColours.size()];
}

}  // namespace sim4cv::render
