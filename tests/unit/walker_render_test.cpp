// A packaged person drawn as a walker keeps ground truth exact: its instance
// id and the semantic class `person` cover the same pixels, its depth is its
// distance, its mask's box is as tall as the person, and the same frame
// renders to the same bytes. Far away, walkers are drawn with a lighter mesh
// (DrawItem::far_mesh), chosen per camera.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/mesh_builder.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/render/walker_looks.h"
#include "server/sim/scene.h"
#include "server/sim/world.h"
#include "sim4cv.pb.h"
#include "tests/support/rendered_frame.h"

namespace sim4cv::render {
namespace {

constexpr uint32_t kWidth = 320, kHeight = 240;
constexpr float kDistance = 5.0f, kFovY = 60.0f;

TEST(WalkerRender, APackagedPersonsGroundTruthIsExact) {
  const auto context = CreateGlContext();
  const sim::Scene scene = sim::DefaultScene(kWidth, kHeight);
  sim::World world(scene);
  sim::State state = world.InitialState();
  const Eigen::Vector3d car = state.Find(sim::kCarEntityId)->body.position;
  const Eigen::Vector3d at(car.x() + 30.0, car.y() + 30.0, 0.0);  // off the road, nothing else near
  const uint32_t id = world.Spawn(state, sim::EntityKind::kPedestrian, "walker", {at, 0.0});
  SceneGraphics graphics(scene);
  graphics.Update(state);

  CameraView camera;
  const Eigen::Vector3f eye = at.cast<float>() + Eigen::Vector3f(kDistance, 0.0f, 0.87f);
  camera.world_from_camera = LookAt(eye, at.cast<float>() + Eigen::Vector3f(0, 0, 0.87f), Eigen::Vector3f::UnitZ());
  camera.previous_world_from_camera = camera.world_from_camera;
  camera.width = kWidth;
  camera.height = kHeight;
  camera.fov_y_deg = kFovY;
  const channels::ChannelSet wanted = channels::Bit(proto::CHANNEL_RGB) | channels::Bit(proto::CHANNEL_DEPTH) |
                                      channels::Bit(proto::CHANNEL_MASK) | channels::Bit(proto::CHANNEL_SEMANTIC);
  Renderer renderer(graphics.meshes(), kWidth, kHeight);
  testing::RenderedFrame frame(kWidth, kHeight), again(kWidth, kHeight);
  renderer.Render(camera, graphics.draw_items(), frame.Buffers(wanted), {});
  renderer.Render(camera, graphics.draw_items(), again.Buffers(wanted), {});

  uint32_t pixels = 0, top = kHeight, bottom = 0;
  for (uint32_t y = 0; y < kHeight; ++y) {
    for (uint32_t x = 0; x < kWidth; ++x) {
      const std::size_t i = std::size_t{y} * kWidth + x;
      const bool walker = frame.mask[i] == id;
      const bool person = frame.semantic[i] == static_cast<uint8_t>(SemanticClass::kPerson);
      ASSERT_EQ(walker, person) << "pixel " << x << "," << y;
      if (!walker) continue;
      ++pixels;
      top = std::min(top, y);
      bottom = std::max(bottom, y);
      EXPECT_GT(frame.depth[i], kDistance - 0.5f);
      EXPECT_LT(frame.depth[i], kDistance + 0.5f);
    }
  }
  // 1.74 m at 5 m: 72 px on 240 rows of a 60-degree view.
  const double expected_px = kHeight * 1.74 / (2.0 * kDistance * std::tan(kFovY / 2.0 * std::numbers::pi / 180.0));
  EXPECT_NEAR(bottom - top + 1, expected_px, 3.0);
  EXPECT_GT(pixels, 900u) << "a person, not a stick";
  EXPECT_EQ(frame.rgb, again.rgb);
  EXPECT_EQ(frame.depth, again.depth);
  EXPECT_EQ(frame.mask, again.mask);
  EXPECT_EQ(frame.semantic, again.semantic);
}

// The rows a labelled instance covers in the mask.
uint32_t RowsOf(const testing::RenderedFrame& frame, InstanceId id) {
  uint32_t top = frame.height, bottom = 0;
  for (uint32_t y = 0; y < frame.height; ++y) {
    for (uint32_t x = 0; x < frame.width; ++x) {
      if (frame.mask[std::size_t{y} * frame.width + x] != id) continue;
      top = std::min(top, y);
      bottom = std::max(bottom, y);
    }
  }
  return top <= bottom ? bottom - top + 1 : 0;
}

// An item with a far mesh is drawn with it, in every channel alike, once
// its mesh spans fewer rows than far_below_px; nearer, with its own mesh.
TEST(LevelOfDetail, TheFarMeshIsDrawnOnceTheItemIsSmallOnScreen) {
  const auto context = CreateGlContext();
  // A 2 m cube and, as its far mesh, a 1 m one: which was drawn shows in the mask's height.
  const std::vector<Mesh> meshes = {MakeBox({1, 1, 1}, {0.5f, 0.5f, 0.5f}), MakeBox({0.5f, 0.5f, 0.5f}, {1, 0, 0})};
  DrawItem item{0, Eigen::Matrix4f::Identity(), 7};
  item.previous_world_from_model = item.world_from_model;
  item.far_mesh = 1;
  item.far_below_px = 60.0f;  // the 2 m cube's sphere (3.46 m across) spans 60 rows at 12 m here
  Renderer renderer(meshes, kWidth, kHeight);
  const auto rows_at = [&](float distance) {
    CameraView camera;
    camera.world_from_camera = LookAt({distance, 0, 0}, {0, 0, 0}, Eigen::Vector3f::UnitZ());
    camera.previous_world_from_camera = camera.world_from_camera;
    camera.width = kWidth;
    camera.height = kHeight;
    camera.fov_y_deg = kFovY;
    testing::RenderedFrame frame(kWidth, kHeight);
    renderer.Render(camera, std::span(&item, 1), frame.Buffers(), {});
    return RowsOf(frame, 7);
  };
  const double focal = kHeight / (2.0 * std::tan(kFovY / 2.0 * std::numbers::pi / 180.0));
  // Nearer than 12 m: the 2 m cube (its front face 1 m nearer than its centre).
  EXPECT_NEAR(rows_at(10.0f), 2.0 * focal / 9.0, 2.0);
  // Farther: the 1 m cube.
  EXPECT_NEAR(rows_at(15.0f), 1.0 * focal / 14.5, 2.0);
}

}  // namespace
}  // namespace sim4cv::render
