#include "server/render/mesh_builder.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <Eigen/Geometry>
#include <numbers>

namespace sim4cv::render {
namespace {

Eigen::Vector3f Position(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }
Eigen::Vector3f Normal(const Vertex& v) { return {v.normal[0], v.normal[1], v.normal[2]}; }

// Indices in range, unit normals, and every triangle counter-clockwise seen
// from the side its normals point to.
void ExpectWellFormed(const Mesh& mesh, size_t max_triangles) {
  ASSERT_FALSE(mesh.vertices.empty());
  ASSERT_EQ(mesh.indices.size() % 3, 0u);
  EXPECT_LE(mesh.indices.size() / 3, max_triangles);
  for (const Vertex& vertex : mesh.vertices) EXPECT_NEAR(Normal(vertex).norm(), 1.0f, 1e-5f);
  for (uint32_t index : mesh.indices) ASSERT_LT(index, mesh.vertices.size());
  for (size_t i = 0; i < mesh.indices.size(); i += 3) {
    const Vertex& a = mesh.vertices[mesh.indices[i]];
    const Vertex& b = mesh.vertices[mesh.indices[i + 1]];
    const Vertex& c = mesh.vertices[mesh.indices[i + 2]];
    const Eigen::Vector3f face_normal = (Position(b) - Position(a)).cross(Position(c) - Position(a));
    ASSERT_GT(face_normal.norm(), 0.0f) << "degenerate triangle " << i / 3;
    EXPECT_GT(face_normal.normalized().dot(Normal(a)), 0.99f) << "triangle " << i / 3 << " winds clockwise";
  }
}

Eigen::AlignedBox3f Bounds(const Mesh& mesh) {
  Eigen::AlignedBox3f bounds;
  for (const Vertex& vertex : mesh.vertices) bounds.extend(Position(vertex));
  return bounds;
}

TEST(MeshBuilder, BoxIsCentredWithOutwardNormals) {
  const Mesh box = MakeBox({1.0f, 2.0f, 0.5f}, {1, 0, 0});
  ExpectWellFormed(box, 12);
  EXPECT_EQ(box.indices.size(), 36u);
  EXPECT_TRUE(Bounds(box).min().isApprox(Eigen::Vector3f(-1.0f, -2.0f, -0.5f)));
  EXPECT_TRUE(Bounds(box).max().isApprox(Eigen::Vector3f(1.0f, 2.0f, 0.5f)));
  for (const Vertex& vertex : box.vertices) EXPECT_GT(Normal(vertex).dot(Position(vertex)), 0.0f);
}

TEST(MeshBuilder, GroundPlaneIsAFewUpwardTrianglesAtZeroHeight) {
  const Mesh ground = MakeGroundPlane(100.0f, {0.3f, 0.5f, 0.3f});
  ExpectWellFormed(ground, 200);
  for (const Vertex& vertex : ground.vertices) {
    EXPECT_EQ(vertex.position[2], 0.0f);
    EXPECT_EQ(vertex.normal[2], 1.0f);
  }
  EXPECT_TRUE(Bounds(ground).max().head<2>().isApprox(Eigen::Vector2f(100.0f, 100.0f)));
}

TEST(MeshBuilder, RoadLoopLiesJustAboveTheGroundWithinItsWidth) {
  const std::vector<Eigen::Vector2f> square = {{-50, -50}, {50, -50}, {50, 50}, {-50, 50}};
  const float lane_width = 3.5f;
  const Mesh road = MakeRoadLoop(square, lane_width, {0.2f, 0.2f, 0.2f}, {1, 1, 1});
  ExpectWellFormed(road, 500);
  for (const Vertex& vertex : road.vertices) {
    EXPECT_GT(vertex.position[2], 0.005f);
    EXPECT_LT(vertex.position[2], 0.1f);
  }
  // Mitred corners reach sqrt(2) * lane_width out; nothing goes further.
  const float reach = 50.0f + lane_width * std::numbers::sqrt2_v<float> + 1e-3f;
  EXPECT_LE(Bounds(road).max().head<2>().maxCoeff(), reach);
  EXPECT_GE(Bounds(road).min().head<2>().minCoeff(), -reach);
  EXPECT_GE(Bounds(road).max().x(), 50.0f + lane_width - 1e-3f);
}

TEST(MeshBuilder, RoadLoopAcceptsAnExplicitlyClosedPolyline) {
  const std::vector<Eigen::Vector2f> triangle = {{0, 0}, {40, 0}, {20, 30}, {0, 0}};
  ExpectWellFormed(MakeRoadLoop(triangle, 3.0f, {0.2f, 0.2f, 0.2f}, {1, 1, 1}), 500);
}

TEST(MeshBuilder, RoadLoopRejectsTooFewPoints) {
  EXPECT_THROW(MakeRoadLoop({{0, 0}, {1, 0}}, 3.0f, {0, 0, 0}, {1, 1, 1}), std::invalid_argument);
}

TEST(MeshBuilder, CarFillsExactlyItsBoundingBox) {
  const Mesh car = MakeCarMesh(4.2f, 1.8f, 1.5f, {0.8f, 0.1f, 0.1f});
  ExpectWellFormed(car, 200);
  EXPECT_TRUE(Bounds(car).min().isApprox(Eigen::Vector3f(-2.1f, -0.9f, -0.75f)));
  EXPECT_TRUE(Bounds(car).max().isApprox(Eigen::Vector3f(2.1f, 0.9f, 0.75f)));
}

TEST(MeshBuilder, EveryCarStyleFillsExactlyTheSameBounds) {
  // One physics box and one 3D box serve every style, so each must reach all six faces.
  for (int style = 0; style < kCarStyleCount; ++style) {
    SCOPED_TRACE(style);
    const Mesh car = MakeCarMesh(4.5f, 1.8f, 1.5f, {0.8f, 0.8f, 0.8f}, static_cast<CarStyle>(style));
    ExpectWellFormed(car, 200);
    EXPECT_TRUE(Bounds(car).min().isApprox(Eigen::Vector3f(-2.25f, -0.9f, -0.75f))) << Bounds(car).min();
    EXPECT_TRUE(Bounds(car).max().isApprox(Eigen::Vector3f(2.25f, 0.9f, 0.75f))) << Bounds(car).max();
    std::size_t glowing = 0;
    for (const Vertex& v : car.vertices) {
      EXPECT_EQ(v.semantic & kSemanticBits, static_cast<uint32_t>(SemanticClass::kCar));
      if ((v.semantic & kEmissive) != 0) ++glowing;
    }
    EXPECT_EQ(glowing, 4u * 24u) << "four lamp boxes glow at night, nothing else";
  }
  // Different silhouettes: the roof's length tells a van from a sedan from a pickup.
  const auto cabin_length = [](CarStyle style) {
    const Mesh car = MakeCarMesh(4.5f, 1.8f, 1.5f, {0.8f, 0.8f, 0.8f}, style);
    float low = 10, high = -10;
    for (const Vertex& v : car.vertices) {
      if (v.position[2] > 0.7f) {  // the roof
        low = std::min(low, v.position[0]);
        high = std::max(high, v.position[0]);
      }
    }
    return high - low;
  };
  EXPECT_GT(cabin_length(CarStyle::kVan), cabin_length(CarStyle::kSedan) + 1.0f);
  EXPECT_LT(cabin_length(CarStyle::kPickup), cabin_length(CarStyle::kSedan));
  EXPECT_GT(cabin_length(CarStyle::kTruck), cabin_length(CarStyle::kVan)) << "cab and cargo box: roof end to end";
}

TEST(MeshBuilder, UavIsCentredAndWithinItsSpan) {
  const float span = 0.5f;
  const Mesh uav = MakeUavMesh(span, {0.9f, 0.9f, 0.2f});
  ExpectWellFormed(uav, 200);
  EXPECT_LT(Bounds(uav).max().head<2>().maxCoeff(), span);
  EXPECT_LT(Bounds(uav).center().head<2>().norm(), 1e-4f);
}

TEST(MeshBuilder, RotorsSpinInsideTheSpan) {
  const float span = 0.5f;
  const UavParts parts = MakeUavParts(span, {0.2f, 0.2f, 0.2f});
  ExpectWellFormed(parts.rotor, 100);
  for (std::size_t rotor = 0; rotor < 4; ++rotor) {
    for (double t = 0.0; t < 0.05; t += 0.0013) {
      for (const Vertex& v : parts.rotor.vertices) {
        const Eigen::Vector4f p = RotorPose(span, rotor, t) * Eigen::Vector4f(v.position[0], v.position[1], v.position[2], 1);
        ASSERT_LT(p.head<2>().cwiseAbs().maxCoeff(), 0.5f * span) << "rotor " << rotor << " at " << t << " s";
      }
    }
    EXPECT_FALSE(RotorPose(span, rotor, 0.0).isApprox(RotorPose(span, rotor, 0.01))) << "it turns";
    EXPECT_TRUE((RotorPose(span, rotor, 0.0).block<3, 1>(0, 3).isApprox(RotorHubs(span)[rotor])));
  }
  // Diagonal pairs turn opposite ways.
  const Eigen::Matrix3f a = RotorPose(span, 0, 0.002).topLeftCorner<3, 3>(), b = RotorPose(span, 2, 0.002).topLeftCorner<3, 3>();
  EXPECT_TRUE(a.isApprox(b.transpose(), 1e-5f));
}

TEST(MeshBuilder, AppendMeshTransformsAndRebasesIndices) {
  Mesh scene = MakeBox({1, 1, 1}, {1, 1, 1});
  Eigen::Matrix4f transform = Eigen::Matrix4f::Identity();
  transform.topLeftCorner<3, 3>() = Eigen::AngleAxisf(0.5f, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  transform.block<3, 1>(0, 3) = Eigen::Vector3f(10, 0, 0);
  AppendMesh(scene, MakeBox({1, 1, 1}, {1, 1, 1}), transform);
  ExpectWellFormed(scene, 24);
  EXPECT_EQ(scene.vertices.size(), 48u);
  EXPECT_NEAR(Bounds(scene).max().x(), 10.0f + std::sqrt(2.0f) * std::cos(0.5f - std::numbers::pi_v<float> / 4),
              1e-4f);
}

TEST(MeshBuilder, AppendMeshKeepsWindingUnderAMirror) {
  Mesh mirrored;
  AppendMesh(mirrored, MakeCarMesh(4, 2, 1.5f, {1, 0, 0}), Eigen::Vector4f(1, -1, 1, 1).asDiagonal());
  ExpectWellFormed(mirrored, 200);
}

}  // namespace
}  // namespace sim4cv::render
