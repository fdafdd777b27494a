// Walker and traffic-light meshes: lean, well formed, the size and facing
// their documentation gives; lit lamps sit in front of their dark ones.
#include "server/render/traffic_meshes.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <vector>

namespace sim4cv::render {
namespace {

using traffic::Signal;

struct Bounds {
  Eigen::Vector3f min = Eigen::Vector3f::Constant(1e9f), max = Eigen::Vector3f::Constant(-1e9f);
};

Bounds BoundsOf(const Mesh& mesh) {
  Bounds b;
  for (const Vertex& v : mesh.vertices) {
    const Eigen::Vector3f p(v.position[0], v.position[1], v.position[2]);
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

void ExpectWellFormed(const Mesh& mesh) {
  ASSERT_EQ(mesh.indices.size() % 3, 0u);
  EXPECT_LE(mesh.indices.size() / 3, 120u);
  for (uint32_t index : mesh.indices) ASSERT_LT(index, mesh.vertices.size());
  for (const Vertex& v : mesh.vertices) {
    EXPECT_NEAR(Eigen::Vector3f(v.normal[0], v.normal[1], v.normal[2]).norm(), 1.0f, 1e-5f);
    for (float c : v.color) {
      EXPECT_GE(c, 0.0f);
      EXPECT_LE(c, 1.0f);
    }
  }
  // Counter-clockwise seen from outside: each face's winding agrees with its normal.
  for (std::size_t i = 0; i < mesh.indices.size(); i += 3) {
    const auto p = [&](int k) {
      const Vertex& v = mesh.vertices[mesh.indices[i + k]];
      return Eigen::Vector3f(v.position[0], v.position[1], v.position[2]);
    };
    const Vertex& first = mesh.vertices[mesh.indices[i]];
    const Eigen::Vector3f normal(first.normal[0], first.normal[1], first.normal[2]);
    EXPECT_GT((p(1) - p(0)).cross(p(2) - p(0)).dot(normal), 0.0f);
  }
}

TEST(TrafficMeshesTest, APedestrianStandsOnItsFeetAtTheOriginAndIsAsTallAsDocumented) {
  std::set<std::vector<float>> looks;
  for (uint32_t variant = 0; variant < 16; ++variant) {
    SCOPED_TRACE(variant);
    const Mesh mesh = MakePedestrianMesh(variant);
    ExpectWellFormed(mesh);
    EXPECT_EQ(mesh.indices.size() / 3, 108u);
    const Bounds b = BoundsOf(mesh);
    EXPECT_NEAR(b.min.z(), 0.0f, 1e-6f);
    EXPECT_NEAR(b.max.z(), kPedestrianHeight, 1e-5f);
    EXPECT_NEAR(b.min.y() + b.max.y(), 0.0f, 1e-5f);  // centred across
    EXPECT_LT(b.max.y() - b.min.y(), 0.7f);           // lean: shoulders and arms
    EXPECT_LT(b.max.x() - b.min.x(), 0.4f);
    EXPECT_GT(b.max.x(), -b.min.x());  // the toes point forward (+x)
    std::vector<float> colours;
    for (const Vertex& v : mesh.vertices) colours.insert(colours.end(), v.color, v.color + 3);
    looks.insert(colours);
    EXPECT_EQ(colours, [&] {
      std::vector<float> again;
      for (const Vertex& v : MakePedestrianMesh(variant).vertices) again.insert(again.end(), v.color, v.color + 3);
      return again;
    }());
  }
  EXPECT_GE(looks.size(), 12u);  // clothes, skin and hair vary
}

TEST(TrafficMeshesTest, ATrafficLightIsAPoleWithLampsFacingPlusX) {
  const Mesh light = MakeTrafficLightMesh();
  ExpectWellFormed(light);
  EXPECT_EQ(light.indices.size() / 3, 96u);
  const Bounds b = BoundsOf(light);
  EXPECT_NEAR(b.min.z(), 0.0f, 1e-6f);
  EXPECT_NEAR(b.max.z(), kTrafficLightHeight, 0.05f);
  EXPECT_LT(b.max.y() - b.min.y(), 0.5f);
  EXPECT_LT(-b.min.x(), 0.2f);  // nothing much behind the pole: the housing's face is +x
  float previous_z = 1e9f;
  for (Signal signal : {Signal::kRed, Signal::kYellow, Signal::kGreen}) {
    SCOPED_TRACE(SignalName(signal));
    const Eigen::Vector3f at = LampOffset(signal);
    EXPECT_LT(at.z(), previous_z);  // red on top, green at the bottom
    previous_z = at.z();
    EXPECT_EQ(at.y(), 0.0f);
    const Mesh lamp = MakeLampMesh(signal);
    ExpectWellFormed(lamp);
    const Bounds lit = BoundsOf(lamp);
    // In front of the dark lamp (a box a little larger than the lit plate)...
    const float reach = lit.max.y() + 0.015f;
    float behind = -1e9f;
    for (const Vertex& v : light.vertices) {
      if (std::abs(v.position[1]) <= reach && std::abs(v.position[2] - at.z()) <= reach) {
        behind = std::max(behind, v.position[0]);
      }
    }
    EXPECT_GT(at.x() + lit.min.x(), behind + 0.001f);
    EXPECT_LT(at.x() + lit.min.x(), behind + 0.02f);  // ...and close to it
    // ...and brighter than the dark lamp it covers.
    float dark = 0, bright = 0;
    for (const Vertex& v : lamp.vertices) bright = std::max({bright, v.color[0], v.color[1], v.color[2]});
    for (const Vertex& v : light.vertices) {
      if (std::abs(v.position[2] - at.z()) < 0.05f && v.position[0] > 0.1f) {
        dark = std::max({dark, v.color[0], v.color[1], v.color[2]});
      }
    }
    EXPECT_GE(bright, 0.99f);
    EXPECT_LT(dark, 0.3f);
  }
}

TEST(TrafficMeshesTest, CrosswalkMarkingsAreFlatStripesAcrossBothLanesFacingUp) {
  // One crosswalk across a north-south road at (10, 20), one across an east-west road.
  const std::vector<traffic::TrafficPlan::Crosswalk> crosswalks = {{{10, 20}, {1, 0}, {0, 1}}, {{-5, 0}, {0, -1}, {1, 0}}};
  const Mesh mesh = MakeCrosswalkMarkings(crosswalks);
  ASSERT_EQ(mesh.indices.size() / 3, 2u * 8u * 2u) << "8 stripes of 2 triangles per crosswalk";
  for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {
    const auto corner = [&](int k) {
      const auto& p = mesh.vertices[mesh.indices[t + k]].position;
      return Eigen::Vector3f(p[0], p[1], p[2]);
    };
    EXPECT_GT((corner(1) - corner(0)).cross(corner(2) - corner(0)).z(), 0.0f) << "counter-clockwise from above";
    for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(corner(k).z(), 0.07f) << "on the road, at the markings' height";
  }
  for (const Vertex& v : mesh.vertices) {
    const bool first = v.position[1] > 10;
    const float across = first ? v.position[0] - 10 : -v.position[1];
    const float along = first ? v.position[1] - 20 : v.position[0] + 5;
    EXPECT_LE(std::abs(across), 4.0f) << "within the road's two lanes";
    EXPECT_LE(std::abs(along), 1.5f + 1e-5f);
  }
}

TEST(TrafficMeshesTest, WalkingLimbsSwingWithTheGaitAndStayInsideTheBox) {
  const PedestrianParts parts = MakePedestrianParts(3);
  float front = 0.0f;
  for (int step = 0; step < 64; ++step) {
    const double phase = 2.0 * std::numbers::pi * step / 64.0;
    const auto limbs = LimbPoses(phase, kMaxLimbSwing);
    for (std::size_t limb = 0; limb < limbs.size(); ++limb) {
      for (const Vertex& v : (limb < 2 ? parts.leg : parts.arm).vertices) {
        const Eigen::Vector4f p = limbs[limb] * Eigen::Vector4f(v.position[0], v.position[1], v.position[2], 1.0f);
        ASSERT_LE(std::abs(p.x()), kPedestrianBox.x() + 1e-5) << "phase " << phase << ", limb " << limb;
        ASSERT_LE(std::abs(p.y()), kPedestrianBox.y() + 1e-5);
        ASSERT_GE(p.z(), -0.05f) << "a swinging foot may not sink into the ground";
        ASSERT_LE(p.z(), kPedestrianHeight);
        if (limb == 0) front = std::max(front, p.x());
      }
    }
  }
  EXPECT_GT(front, 0.4f) << "a full stride reaches forward";
  // Standing: the limbs hang straight, as in the one-piece mesh.
  for (const Eigen::Matrix4f& pose : LimbPoses(1.0, LimbSwing(0.0))) {
    EXPECT_TRUE((pose.topLeftCorner<3, 3>().isIdentity(1e-6f)));
  }
  // One gait cycle per stride along the heading, whatever the heading.
  const double heading = 0.7;
  const Eigen::Vector2d start(3, -4), ahead = start + kStrideM * Eigen::Vector2d(std::cos(heading), std::sin(heading));
  EXPECT_NEAR(GaitPhase(ahead, heading) - GaitPhase(start, heading), 2.0 * std::numbers::pi, 1e-9);
  EXPECT_GT(LimbSwing(1.4), LimbSwing(0.5));
  EXPECT_EQ(LimbSwing(5.0), kMaxLimbSwing);
}

TEST(TrafficMeshesTest, TrafficCarColoursDifferFromNeighboursAndFromTheSimulatedVehicles) {
  for (uint32_t variant = 0; variant < 40; ++variant) {
    const Eigen::Vector3f colour = TrafficCarColour(variant);
    EXPECT_EQ(colour, TrafficCarColour(variant));
    EXPECT_GE(colour.minCoeff(), 0.0f);
    EXPECT_LE(colour.maxCoeff(), 1.0f);
    EXPECT_NE(colour, TrafficCarColour(variant + 1));
    EXPECT_GT((colour - Eigen::Vector3f(0.80f, 0.10f, 0.10f)).norm(), 0.2f);  // the target car
    EXPECT_GT((colour - Eigen::Vector3f(0.15f, 0.30f, 0.75f)).norm(), 0.2f);  // the UAV
  }
}

}  // namespace
}  // namespace sim4cv::render
