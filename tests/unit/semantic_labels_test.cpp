// Semantic labels: the class table follows the Cityscapes convention, and
// every surface of the shipped scenes is labelled: rendering them with
// CHANNEL_SEMANTIC leaves no pixel unlabelled, and shows the classes the
// scene is made of.
#include "protocol/semantic_classes.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"
#include "tests/support/rendered_frame.h"
#include "tests/unit/traffic_test_support.h"

namespace sim4cv::render {
namespace {

using Class = SemanticClass;
using semantic::kSemanticClasses;
using semantic::SemanticClassInfo;

TEST(SemanticClassesTest, CityscapesTrainIdsAndPaletteWhereCityscapesHasTheClass) {
  std::set<int> ids;
  for (const SemanticClassInfo& info : kSemanticClasses) {
    EXPECT_TRUE(ids.insert(static_cast<int>(info.id)).second) << info.name << " repeats an id";
    const int id = static_cast<int>(info.id);
    if (id <= 18) {
      EXPECT_EQ(info.cityscapes_train_id, id) << info.name << " is a Cityscapes class";
    }
    EXPECT_TRUE(info.cityscapes_train_id <= 18 || info.cityscapes_train_id == 255) << info.name;
  }
  const auto colour = [](Class c) { return kSemanticClasses[static_cast<std::size_t>(c)].colour; };
  EXPECT_EQ(colour(Class::kRoad), (std::array<uint8_t, 3>{128, 64, 128}));
  EXPECT_EQ(colour(Class::kCar), (std::array<uint8_t, 3>{0, 0, 142}));
  EXPECT_EQ(colour(Class::kSky), (std::array<uint8_t, 3>{70, 130, 180}));
  EXPECT_EQ(colour(Class::kVegetation), (std::array<uint8_t, 3>{107, 142, 35}));
  EXPECT_EQ(kSemanticClasses[static_cast<std::size_t>(Class::kLaneMarking)].cityscapes_train_id, 0) << "folds into road";
}

// Renders `scene`'s items from `camera` with the semantic channel and counts the classes.
std::map<int, uint32_t> ClassesSeen(const sim::Scene& scene, const CameraView& camera) {
  const auto context = CreateGlContext();
  SceneGraphics graphics(scene);
  const sim::World world(scene);
  graphics.Update(world.InitialState());
  Renderer renderer(graphics.meshes(), camera.width, camera.height);
  testing::RenderedFrame frame(camera.width, camera.height);
  renderer.Render(camera, graphics.draw_items(), frame.Buffers(channels::Bit(proto::CHANNEL_SEMANTIC)), {});
  std::map<int, uint32_t> seen;
  for (uint8_t id : frame.semantic) ++seen[id];
  return seen;
}

CameraView Looking(const Eigen::Vector3f& eye, const Eigen::Vector3f& at, uint32_t width = 320, uint32_t height = 240) {
  CameraView camera;
  camera.world_from_camera = LookAt(eye, at, Eigen::Vector3f::UnitZ());
  camera.previous_world_from_camera = camera.world_from_camera;
  camera.width = width;
  camera.height = height;
  camera.fov_y_deg = 70.0f;
  return camera;
}

bool Has(const std::map<int, uint32_t>& seen, Class c) { return seen.count(static_cast<int>(c)) != 0; }

std::string Dump(const std::map<int, uint32_t>& seen) {
  std::string text;
  for (const auto& [id, count] : seen) text += std::to_string(id) + ":" + std::to_string(count) + " ";
  return text;
}

TEST(SemanticLabelsTest, DefaultSceneIsLabelledEverywhere) {
  const sim::Scene scene = sim::DefaultScene(320, 180);
  const sim::World world(scene);
  const Eigen::Vector3d car = world.InitialState().Find(sim::kCarEntityId)->body.position;
  const auto seen = ClassesSeen(scene, Looking(car.cast<float>() + Eigen::Vector3f(-12, 0, 6), car.cast<float>()));
  EXPECT_FALSE(Has(seen, Class::kUnlabelled)) << Dump(seen);
  for (Class c : {Class::kRoad, Class::kLaneMarking, Class::kTerrain, Class::kCar, Class::kSky}) {
    EXPECT_TRUE(Has(seen, c)) << static_cast<int>(c) << " missing: " << Dump(seen);
  }
}

TEST(SemanticLabelsTest, UrbanMapWithTrafficIsLabelledEverywhere) {
  sim::Scene scene = sim::SceneFromMap((traffic::testing::SourceDir() / "scenes/driving/train/01_urban.map").string(),
                                       "", 6.0f, 320, 180);
  traffic::TrafficConfig config;
  config.moving_cars = 10;
  config.parked_cars = 20;
  config.pedestrians = 20;
  sim::AddTraffic(scene, config);
  const sim::World world(scene);
  const Eigen::Vector3f car = world.InitialState().Find(sim::kCarEntityId)->body.position.cast<float>();
  std::map<int, uint32_t> all;
  // From the car's height ahead and from above: every class a street shows.
  for (const CameraView& camera : {Looking(car + Eigen::Vector3f(0, 0, 30), car + Eigen::Vector3f(0.1f, 0, 0)),
                                   Looking(car + Eigen::Vector3f(-15, -15, 12), car),
                                   Looking(car + Eigen::Vector3f(0, 0, 120), car + Eigen::Vector3f(0.1f, 0, 0))}) {
    const auto seen = ClassesSeen(scene, camera);
    EXPECT_FALSE(Has(seen, Class::kUnlabelled)) << Dump(seen);
    for (const auto& [id, count] : seen) all[id] += count;
  }
  for (Class c : {Class::kRoad, Class::kSidewalk, Class::kLaneMarking, Class::kBuilding, Class::kCar,
                  Class::kTerrain}) {
    EXPECT_TRUE(Has(all, c)) << static_cast<int>(c) << " missing: " << Dump(all);
  }
}

}  // namespace
}  // namespace sim4cv::render
