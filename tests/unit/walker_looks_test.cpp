// Walkers drawn from the packaged people: the bundle the build converted is
// whole and lean, every person is a walker's height and stays inside the
// walker's 3D box with its feet on the ground whatever the sway, the look is
// a fixed function of the instance id, and a damaged bundle is refused with
// a message saying what is wrong.
#include "server/render/walker_looks.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <numbers>
#include <set>
#include <stdexcept>
#include <vector>

#include "server/render/people_bundle.h"
#include "server/render/traffic_meshes.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::render {
namespace {

Eigen::Vector3f PositionOf(const Vertex& v) { return {v.position[0], v.position[1], v.position[2]}; }

// Every mesh of every person, full and far.
std::vector<const Mesh*> AllMeshes() {
  std::vector<const Mesh*> meshes;
  for (const Person& person : PeopleMeshes()) {
    meshes.push_back(&person.full);
    meshes.push_back(&person.far);
  }
  return meshes;
}

TEST(PeopleBundle, HoldsSeveralLeanPeople) {
  const std::vector<Person>& people = PeopleMeshes();
  ASSERT_GE(people.size(), 4u) << "built without sweethome3d-furniture? (bash scripts/setup.sh, then rebuild)";
  for (const Person& person : people) {
    EXPECT_GE(person.full.indices.size() / 3, 1500u);
    EXPECT_LE(person.full.indices.size() / 3, 3000u);
    EXPECT_GE(person.far.indices.size() / 3, 500u);
    EXPECT_LE(person.far.indices.size() / 3, 900u);
  }
  for (const Mesh* mesh : AllMeshes()) {
    for (const Vertex& v : mesh->vertices) {
      EXPECT_EQ(v.semantic, static_cast<uint32_t>(SemanticClass::kPerson));
      EXPECT_NEAR(Eigen::Vector3f(v.normal[0], v.normal[1], v.normal[2]).norm(), 1.0f, 1e-3f);
      for (const float c : v.color) EXPECT_TRUE(c >= 0.0f && c <= 1.0f);
    }
  }
}

TEST(PeopleBundle, EveryPersonStaysInTheWalkerBoxWithFeetOnTheGround) {
  for (const Mesh* mesh : AllMeshes()) {
    const Mesh& person = *mesh;
    float lowest_at_rest = 1e9f, highest_at_rest = -1e9f;
    for (const Vertex& v : person.vertices) {
      lowest_at_rest = std::min(lowest_at_rest, v.position[2]);
      highest_at_rest = std::max(highest_at_rest, v.position[2]);
    }
    EXPECT_NEAR(lowest_at_rest, 0.0f, 0.01f);
    EXPECT_NEAR(highest_at_rest, kPedestrianHeight, 0.02f);
    for (double phase = 0.0; phase < 2.0 * std::numbers::pi; phase += 0.25) {
      const Eigen::Matrix4f sway = SwayPose(phase, 2.0);
      float lowest = 1e9f;
      for (const Vertex& v : person.vertices) {
        const Eigen::Vector3f p = (sway * PositionOf(v).homogeneous()).head<3>();
        EXPECT_LE(std::abs(p.x()), kPedestrianBox.x());
        EXPECT_LE(std::abs(p.y()), kPedestrianBox.y());
        EXPECT_LE(p.z(), 2.0 * kPedestrianBox.z());
        lowest = std::min(lowest, p.z());
      }
      // Rolling on the point between the feet lifts or sinks a foot by at most its offset times the lean.
      EXPECT_NEAR(lowest, 0.0f, 0.015f) << "phase " << phase;
    }
  }
}

TEST(WalkerLooks, TheLookIsAFixedFunctionOfTheId) {
  std::vector<Mesh> meshes;
  const WalkerLooks looks([&](Mesh mesh) {
    meshes.push_back(std::move(mesh));
    return static_cast<MeshId>(meshes.size() - 1);
  });
  ASSERT_TRUE(looks.packaged());
  EXPECT_EQ(meshes.size(), 2 * PeopleMeshes().size());
  std::set<MeshId> seen;
  for (InstanceId id = 1; id <= 40; ++id) {
    std::vector<DrawItem> first, again;
    looks.Append(first, id, Eigen::Matrix4f::Identity(), {3.0 * id, 1.0}, 0.3, 1.2);
    looks.Append(again, id, Eigen::Matrix4f::Identity(), {3.0 * id, 1.0}, 0.3, 1.2);
    ASSERT_EQ(first.size(), 1u);
    ASSERT_EQ(again.size(), 1u);
    EXPECT_EQ(first[0].mesh, again[0].mesh);
    EXPECT_EQ(first[0].far_mesh, again[0].far_mesh);
    EXPECT_NE(first[0].far_mesh, first[0].mesh);
    EXPECT_EQ(first[0].far_below_px, kFarPersonBelowPx);
    EXPECT_EQ(first[0].instance, id);
    EXPECT_TRUE(first[0].world_from_model.isApprox(again[0].world_from_model));
    seen.insert(first[0].mesh);
  }
  EXPECT_EQ(seen.size(), PeopleMeshes().size()) << "forty walkers show every person";
}

TEST(WalkerLooks, WithoutPackagedPeopleWalkersAreProceduralAndItSaysSo) {
  testing::ExpectLogged("no packaged people (built without sweethome3d-furniture, docs/assets.md)");
  std::vector<Mesh> meshes;
  const WalkerLooks looks(
      [&](Mesh mesh) {
        meshes.push_back(std::move(mesh));
        return static_cast<MeshId>(meshes.size() - 1);
      },
      {});
  EXPECT_FALSE(looks.packaged());
  std::vector<DrawItem> items;
  looks.Append(items, 9, Eigen::Matrix4f::Identity(), {1.0, 2.0}, 0.0, 1.4);
  ASSERT_EQ(items.size(), 5u) << "a body and four limbs";
  for (const DrawItem& item : items) EXPECT_EQ(item.instance, 9);
}

TEST(WalkerLooks, StandingStillIsUpright) {
  EXPECT_TRUE(SwayPose(1.0, 0.0).isApprox(Eigen::Matrix4f::Identity()));
}

// One person whose full and far meshes are one triangle each (the far one 2 m tall).
std::vector<unsigned char> OnePersonBundle() {
  std::vector<unsigned char> bytes = {'S', '4', 'C', 'V', 'P', 'P', 'L', '2'};
  const auto put_u32 = [&](uint32_t value) {
    const auto* p = reinterpret_cast<const unsigned char*>(&value);
    bytes.insert(bytes.end(), p, p + 4);
  };
  put_u32(1);
  put_u32(2);
  for (const float top : {1.0f, 2.0f}) {
    put_u32(3);
    put_u32(3);
    for (int vertex = 0; vertex < 3; ++vertex) {
      const float v[9] = {static_cast<float>(vertex), 0, vertex == 2 ? top : 0.0f, 0, -1, 0, 0.5f, 0.5f, 0.5f};
      const auto* p = reinterpret_cast<const unsigned char*>(v);
      bytes.insert(bytes.end(), p, p + sizeof v);
    }
    for (uint32_t index : {0u, 1u, 2u}) put_u32(index);
  }
  return bytes;
}

std::string ParseError(const std::vector<unsigned char>& bytes) {
  try {
    ParsePeopleBundle(bytes);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "(accepted)";
}

TEST(PeopleBundle, ParsesAWholeBundleAndRefusesDamagedOnes) {
  const std::vector<unsigned char> good = OnePersonBundle();
  const std::vector<Person> people = ParsePeopleBundle(good);
  ASSERT_EQ(people.size(), 1u);
  EXPECT_EQ(people[0].full.indices, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(people[0].full.vertices[2].position[2], 1.0f);
  EXPECT_EQ(people[0].far.vertices[2].position[2], 2.0f);

  std::vector<unsigned char> bad_magic = good;
  bad_magic[7] = '1';
  EXPECT_EQ(ParseError(bad_magic), "people bundle: not a bundle (magic)");
  const std::vector<unsigned char> truncated(good.begin(), good.end() - 2);
  EXPECT_EQ(ParseError(truncated), "people bundle: truncated in the indices at byte 260 of 270");
  std::vector<unsigned char> bad_index = good;
  bad_index[bad_index.size() - 4] = 3;
  EXPECT_EQ(ParseError(bad_index), "people bundle: an index past the model's vertices");
  std::vector<unsigned char> trailing = good;
  trailing.push_back(0);
  EXPECT_EQ(ParseError(trailing), "people bundle: bytes left after the last person");
  std::vector<unsigned char> one_level = good;
  one_level[12] = 1;
  EXPECT_EQ(ParseError(one_level), "people bundle: 1 levels of detail, not 2");
  std::vector<unsigned char> huge = good;
  huge[16] = 0xFF;  // the vertex count's low byte
  huge[19] = 0x7F;
  EXPECT_EQ(ParseError(huge), "people bundle: a model's counts do not fit (2130706687 vertices, 3 indices)");
}

}  // namespace
}  // namespace sim4cv::render
