// The per-object 3D ground truth (server/render/object_catalog.*): static
// boxes from meshes, moving boxes from State, which objects a frame lists,
// and that a warm Fill allocates nothing (it runs on the sim thread).
#include "server/render/object_catalog.h"

#include <gtest/gtest.h>

#include <numbers>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/mesh_builder.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"
#include "tests/support/allocation_counter.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::render {
namespace {

constexpr uint32_t kCarClass = 1, kUavClass = 2, kBuildingClass = 3;

// At the origin looking along world +x, z up, 320x180, 60 degrees.
BoxProjector ForwardCamera() {
  CameraView view;
  view.world_from_camera = LookAt({0, 0, 0}, {1, 0, 0}, {0, 0, 1});
  view.width = 320;
  view.height = 180;
  return BoxProjector(view);
}

// A house-like mesh in its own frame: standing on z = 0, not centred on its origin.
Mesh StandingBox(const Eigen::Vector3f& half) {
  Mesh mesh = MakeBox(half, {0.5f, 0.5f, 0.5f});
  for (Vertex& v : mesh.vertices) v.position[2] += half.z();
  return mesh;
}

GroundTruthBox VisibleBox(InstanceId instance) {
  GroundTruthBox box;
  box.instance = instance;
  return box;
}

class ObjectCatalogTest : public ::testing::Test {
 protected:
  ObjectCatalogTest() {
    // Ahead; ahead but turned a quarter; behind the camera. Added out of order.
    const Eigen::Quaternionf quarter(Eigen::AngleAxisf(std::numbers::pi_v<float> / 2, Eigen::Vector3f::UnitZ()));
    catalog_.AddStatic(120, kBuildingClass, StandingBox({1, 2, 3}), PoseMatrix({-20, 0, 0}, {1, 0, 0, 0}));
    catalog_.AddStatic(110, kBuildingClass, StandingBox({1, 2, 3}), PoseMatrix({30, 5, -3}, quarter));
    catalog_.AddStatic(100, kBuildingClass, StandingBox({1, 2, 3}), PoseMatrix({20, 0, -1}, {1, 0, 0, 0}));
    // The moving objects, ordered by id as SceneGraphics lists them.
    MovingObject car;
    car.instance = 1;
    car.object_class = kCarClass;
    car.position = {10, 1, 0};
    car.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
    car.linear_velocity = {5, 1, 0};
    car.angular_velocity = {0, 0, 0.2};
    car.half_extents = {2.25, 0.9, 0.6};
    MovingObject uav;
    uav.instance = 2;
    uav.object_class = kUavClass;
    uav.position = {0, 0, 5};  // straight above the camera: out of view
    uav.half_extents = {0.3, 0.3, 0.05};
    moving_ = {car, uav};
  }

  MovingObject& car() { return moving_[0]; }

  ObjectCatalog catalog_;
  std::vector<MovingObject> moving_;
};

TEST_F(ObjectCatalogTest, StaticBoxIsCentredOnItsMeshNotOnItsOrigin) {
  std::vector<ObjectGroundTruth> out;
  catalog_.Fill(moving_, ForwardCamera(), {}, out);
  ASSERT_EQ(catalog_.size(), 3u) << "the static objects";
  ASSERT_GE(out.size(), 2u);
  const ObjectGroundTruth& building = out[1];
  ASSERT_EQ(building.instance, 100);
  EXPECT_EQ(building.object_class, kBuildingClass);
  EXPECT_LT((building.position - Eigen::Vector3d(20, 0, 2)).norm(), 1e-6);
  EXPECT_LT((building.half_extents - Eigen::Vector3d(1, 2, 3)).norm(), 1e-6);
  EXPECT_TRUE(building.orientation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_TRUE(building.linear_velocity.isZero(0.0));
  EXPECT_TRUE(building.angular_velocity.isZero(0.0));

  const ObjectGroundTruth& turned = out[2];
  ASSERT_EQ(turned.instance, 110);
  EXPECT_LT((turned.position - Eigen::Vector3d(30, 5, 0)).norm(), 1e-6);
  EXPECT_NEAR(turned.orientation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()))),
              0.0, 1e-6);
}

TEST_F(ObjectCatalogTest, MovingObjectsAreListedAsGiven) {
  std::vector<ObjectGroundTruth> out;
  catalog_.Fill(moving_, ForwardCamera(), {}, out);
  ASSERT_FALSE(out.empty());
  const ObjectGroundTruth& listed = out[0];
  ASSERT_EQ(listed.instance, 1);
  EXPECT_EQ(listed.object_class, kCarClass);
  EXPECT_EQ(listed.position, car().position);
  EXPECT_TRUE(listed.orientation.isApprox(car().orientation));
  EXPECT_EQ(listed.linear_velocity, car().linear_velocity);
  EXPECT_EQ(listed.angular_velocity, car().angular_velocity);
  EXPECT_EQ(listed.half_extents, Eigen::Vector3d(2.25, 0.9, 0.6));
  EXPECT_EQ(listed.projected_box.x,
            ForwardCamera().Project(listed.position, listed.orientation, listed.half_extents).x);

  car().position.x() = 40;
  catalog_.Fill(moving_, ForwardCamera(), {}, out);
  EXPECT_EQ(out[0].position.x(), 40);
}

TEST_F(ObjectCatalogTest, ListsObjectsInViewVisibleOrNotOrderedById) {
  std::vector<ObjectGroundTruth> out;
  const std::vector<GroundTruthBox> visible = {VisibleBox(1), VisibleBox(110)};
  catalog_.Fill(moving_, ForwardCamera(), visible, out);
  // The UAV (above) and building 120 (behind) are out of view.
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].instance, 1);
  EXPECT_TRUE(out[0].has_visible_box);
  EXPECT_EQ(out[1].instance, 100);
  EXPECT_FALSE(out[1].has_visible_box) << "in view but occluded";
  EXPECT_EQ(out[2].instance, 110);
  EXPECT_TRUE(out[2].has_visible_box);
  for (const ObjectGroundTruth& object : out) EXPECT_FALSE(object.projected_box.empty()) << object.instance;
}

TEST_F(ObjectCatalogTest, ObjectWithAVisibleBoxIsListedEvenIfItsProjectionIsEmpty) {
  // Cannot happen with consistent inputs; the visible box still wins.
  std::vector<ObjectGroundTruth> out;
  catalog_.Fill(moving_, ForwardCamera(), std::vector<GroundTruthBox>{VisibleBox(120)}, out);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back().instance, 120);
  EXPECT_TRUE(out.back().has_visible_box);
  EXPECT_TRUE(out.back().projected_box.empty());
}

TEST_F(ObjectCatalogTest, LabellingAnIdTwiceThrows) {
  EXPECT_THROW(catalog_.AddStatic(100, kBuildingClass, StandingBox({1, 1, 1}), Eigen::Matrix4f::Identity()),
               std::invalid_argument);
  EXPECT_THROW(catalog_.AddStatic(130, kBuildingClass, Mesh{}, Eigen::Matrix4f::Identity()), std::invalid_argument);
}

TEST_F(ObjectCatalogTest, WarmFillAllocatesNothing) {
  std::vector<ObjectGroundTruth> out;
  const std::vector<GroundTruthBox> visible = {VisibleBox(1), VisibleBox(100)};
  const BoxProjector camera = ForwardCamera();
  catalog_.Fill(moving_, camera, visible, out);  // warms `out` up
  EXPECT_EQ(testing::AllocationsIn([&] {
              for (int frame = 0; frame < 100; ++frame) {
                car().position.x() = 5.0 + frame * 0.1;
                catalog_.Fill(moving_, camera, visible, out);
              }
            }),
            0u);
}

TEST(SceneGraphicsCatalog, DefaultSceneLabelsTheSameObjectsItDraws) {
  const sim::Scene scene = sim::DefaultScene(320, 180);
  SceneGraphics graphics(scene);
  const sim::World world(scene);
  graphics.Update(world.InitialState());
  ASSERT_EQ(graphics.catalog().size() + graphics.moving_objects().size(), graphics.labelled_objects().size());
  ASSERT_EQ(graphics.moving_objects().size(), 2u) << "the car and the UAV";
  std::vector<ObjectGroundTruth> out;
  CameraView overhead;  // 300 m above the middle, looking down: sees everything
  overhead.world_from_camera = LookAt({0, 0, 300}, {0, 0, 0}, {0, 1, 0});
  graphics.catalog().Fill(graphics.moving_objects(), BoxProjector(overhead), {}, out);
  ASSERT_EQ(out.size(), graphics.labelled_objects().size());
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    const sim::BuildingSpec& b = scene.buildings[i];
    const ObjectGroundTruth& building = out[i + 2];  // after the car and the UAV
    ASSERT_EQ(building.instance, b.id);
    EXPECT_EQ(building.object_class, kBuildingClass);
    EXPECT_NEAR(building.position.x(), b.centre.x(), 1e-4);
    EXPECT_NEAR(building.position.y(), b.centre.y(), 1e-4);
    EXPECT_NEAR(building.position.z(), b.height / 2, 1e-4);
    EXPECT_NEAR(building.half_extents.z(), b.height / 2, 1e-4);
  }
}

}  // namespace
}  // namespace sim4cv::render
