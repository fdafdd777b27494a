// The content of the pixel channels added with the channel registry
// (semantic, normals, flow), checked against values computed by hand from the
// pinhole model, on the real OSMesa renderer.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/mesh_builder.h"
#include "server/render/renderer.h"
#include "tests/support/rendered_frame.h"

namespace sim4cv::render {
namespace {

using testing::RenderedFrame;

constexpr uint32_t kWidth = 160, kHeight = 120;
constexpr MeshId kWall = 0;  // 0.1 m thick, 40 m square, facing -x
constexpr MeshId kCube = 1;  // 1 m, semantic class kCarClass
constexpr uint32_t kCarClass = 13;
constexpr uint8_t kSky = 10;
constexpr float kWallX = 10.0f;
// fov_y 60 degrees: f = (height / 2) / tan(30 degrees).
const float kFocal = 0.5f * kHeight / std::tan(30.0f * std::numbers::pi_v<float> / 180.0f);

channels::ChannelSet Set(std::initializer_list<proto::Channel> list) {
  channels::ChannelSet set = 0;
  for (auto c : list) set |= channels::Bit(c);
  return set;
}

Mesh Labelled(Mesh mesh, uint32_t semantic) {
  for (Vertex& v : mesh.vertices) v.semantic = semantic;
  return mesh;
}

// At the origin looking along world +x, z up: OpenCV x right = world -y,
// y down = world -z, z forward = world +x.
CameraView Camera(const Eigen::Vector3f& eye = Eigen::Vector3f::Zero()) {
  CameraView camera;
  camera.world_from_camera = LookAt(eye, eye + Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitZ());
  camera.previous_world_from_camera = camera.world_from_camera;
  camera.width = kWidth;
  camera.height = kHeight;
  return camera;
}

DrawItem Item(MeshId mesh, const Eigen::Vector3f& position, float yaw = 0.0f) {
  DrawItem item{mesh, PoseMatrix(position, Eigen::Quaternionf(Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()))), 1};
  item.previous_world_from_model = item.world_from_model;
  return item;
}

class ChannelRenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    context_ = CreateGlContext();
    renderer_ = std::make_unique<Renderer>(
        std::vector<Mesh>{Labelled(MakeBox({0.05f, 20.0f, 20.0f}, {0.5f, 0.5f, 0.5f}), 2),
                          Labelled(MakeBox({0.5f, 0.5f, 0.5f}, {0.8f, 0.2f, 0.1f}), kCarClass)},
        kWidth, kHeight);
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    context_.reset();
  }

  static RenderedFrame Render(const std::vector<DrawItem>& items, const CameraView& camera,
                              channels::ChannelSet set) {
    RenderedFrame frame(kWidth, kHeight);
    std::fill(frame.flow.begin(), frame.flow.end(), -1234.0f);  // untouched unless drawn
    renderer_->Render(camera, items, frame.Buffers(set), {});
    return frame;
  }

  static std::unique_ptr<GlContext> context_;
  static std::unique_ptr<Renderer> renderer_;
};

std::unique_ptr<GlContext> ChannelRenderTest::context_;
std::unique_ptr<Renderer> ChannelRenderTest::renderer_;

const channels::ChannelSet kAll =
    Set({proto::CHANNEL_DEPTH, proto::CHANNEL_SEMANTIC, proto::CHANNEL_NORMALS, proto::CHANNEL_FLOW});

TEST_F(ChannelRenderTest, NormalsOfAFaceSeenHeadOnPointAtTheCamera) {
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0})}, Camera(), kAll);
  for (uint32_t y = 0; y < kHeight; ++y) {
    for (uint32_t x = 0; x < kWidth; ++x) {
      const float* n = &frame.normals[frame.At(x, y) * 3];
      ASSERT_NEAR(n[0], 0.0f, 1e-4f) << x << "," << y;
      ASSERT_NEAR(n[1], 0.0f, 1e-4f) << x << "," << y;
      ASSERT_NEAR(n[2], -1.0f, 1e-4f) << x << "," << y;
    }
  }
}

TEST_F(ChannelRenderTest, NormalsOfATiltedFaceFollowTheRotation) {
  // The wall turned by 30 degrees about the vertical (the camera's y axis):
  // its normal, world (-cos a, -sin a, 0), is (sin a, 0, -cos a) in OpenCV axes.
  const float a = 30.0f * std::numbers::pi_v<float> / 180.0f;
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0}, a)}, Camera(), kAll);
  const float* n = &frame.normals[frame.At(kWidth / 2, kHeight / 2) * 3];
  EXPECT_NEAR(n[0], std::sin(a), 1e-4f);
  EXPECT_NEAR(n[1], 0.0f, 1e-4f);
  EXPECT_NEAR(n[2], -std::cos(a), 1e-4f);
}

TEST_F(ChannelRenderTest, SkyHasZeroNormalsZeroFlowAndTheSkyClass) {
  const RenderedFrame frame = Render({Item(kCube, {5, 0, 0})}, Camera(), kAll);
  uint32_t sky = 0, cube = 0;
  for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
    if (std::isinf(frame.depth[i])) {
      ++sky;
      ASSERT_EQ(frame.semantic[i], kSky);
      ASSERT_EQ(frame.normals[3 * i] == 0.0f && frame.normals[3 * i + 1] == 0.0f && frame.normals[3 * i + 2] == 0.0f,
                true);
      ASSERT_EQ(frame.flow[2 * i] == 0.0f && frame.flow[2 * i + 1] == 0.0f, true);
    } else {
      ++cube;
      ASSERT_EQ(frame.semantic[i], kCarClass) << "pixel " << i;
      const float* n = &frame.normals[3 * i];
      ASSERT_NEAR(std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), 1.0f, 1e-4f);
    }
  }
  EXPECT_GT(sky, 0u);
  EXPECT_GT(cube, 100u);
}

TEST_F(ChannelRenderTest, CameraTranslatingSidewaysGivesThePinholeFlow) {
  // The camera was 0.5 m to the left (world +y) a frame ago and moved right:
  // a static point at depth Z moved left in the image by f * t / Z.
  constexpr float kShift = 0.5f;
  CameraView camera = Camera();
  camera.previous_world_from_camera = Camera({0, kShift, 0}).world_from_camera;
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0})}, camera, kAll);
  for (uint32_t y = 0; y < kHeight; y += 7) {
    for (uint32_t x = 0; x < kWidth; x += 5) {
      const std::size_t i = frame.At(x, y);
      ASSERT_FALSE(std::isinf(frame.depth[i]));
      EXPECT_NEAR(frame.flow[2 * i], -kFocal * kShift / frame.depth[i], 0.05f) << x << "," << y;
      EXPECT_NEAR(frame.flow[2 * i + 1], 0.0f, 0.05f) << x << "," << y;
    }
  }
  EXPECT_NEAR(frame.flow[2 * frame.At(80, 60)], -kFocal * kShift / (kWallX - 0.05f), 0.05f);
}

TEST_F(ChannelRenderTest, CameraMovingForwardGivesFlowAwayFromTheCentre) {
  // Z shrinks from Z + d to Z: a pixel at offset u from the principal point
  // came from u * Z / (Z + d), so its flow is u * d / (Z + d).
  constexpr float kForward = 1.0f;
  CameraView camera = Camera();
  camera.previous_world_from_camera = Camera({-kForward, 0, 0}).world_from_camera;
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0})}, camera, kAll);
  const float z = kWallX - 0.05f;
  for (const auto& [x, y] : {std::pair{10u, 10u}, {150u, 100u}, {80u, 60u}, {30u, 90u}}) {
    const std::size_t i = frame.At(x, y);
    const float u = x + 0.5f - kWidth / 2.0f, v = y + 0.5f - kHeight / 2.0f;
    EXPECT_NEAR(frame.flow[2 * i], u * kForward / (z + kForward), 0.05f) << x << "," << y;
    EXPECT_NEAR(frame.flow[2 * i + 1], v * kForward / (z + kForward), 0.05f) << x << "," << y;
  }
}

TEST_F(ChannelRenderTest, AnObjectMovingInFrontOfAStaticCameraFlowsByItsDisplacement) {
  // The cube was 0.3 m to the left (world +y) a frame ago: its front face, at
  // depth 4.5 m, moved right by f * 0.3 / 4.5 px; the static wall did not move.
  constexpr float kMove = 0.3f;
  DrawItem cube = Item(kCube, {5, 0, 0});
  cube.previous_world_from_model = PoseMatrix({5, kMove, 0}, Eigen::Quaternionf::Identity());
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0}), cube}, Camera(), kAll);
  uint32_t cube_pixels = 0;
  for (uint32_t i = 0; i < kWidth * kHeight; ++i) {
    if (frame.semantic[i] == kCarClass) {
      ++cube_pixels;
      ASSERT_NEAR(frame.depth[i], 4.5f, 1e-3f);
      ASSERT_NEAR(frame.flow[2 * i], kFocal * kMove / 4.5f, 0.05f) << "pixel " << i;
      ASSERT_NEAR(frame.flow[2 * i + 1], 0.0f, 0.05f) << "pixel " << i;
    } else {
      ASSERT_NEAR(frame.flow[2 * i], 0.0f, 1e-3f) << "pixel " << i;  // float round-off only
      ASSERT_NEAR(frame.flow[2 * i + 1], 0.0f, 1e-3f) << "pixel " << i;
    }
  }
  EXPECT_GT(cube_pixels, 100u);
}

TEST_F(ChannelRenderTest, PointsBehindThePreviousCameraHaveNoFlow) {
  CameraView camera = Camera();
  camera.previous_world_from_camera = LookAt({0, 0, 0}, {-1, 0, 0}, {0, 0, 1});  // it looked the other way
  const RenderedFrame frame = Render({Item(kWall, {kWallX, 0, 0})}, camera, kAll);
  EXPECT_TRUE(std::isnan(frame.flow[0]) && std::isnan(frame.flow[1]));
  EXPECT_TRUE(std::isnan(frame.flow[2 * frame.At(80, 60)]));
}

TEST_F(ChannelRenderTest, OnlyTheChannelsAskedForAreWritten) {
  RenderedFrame frame(kWidth, kHeight);
  std::fill(frame.depth.begin(), frame.depth.end(), -7.0f);
  std::fill(frame.flow.begin(), frame.flow.end(), -7.0f);
  std::fill(frame.semantic.begin(), frame.semantic.end(), uint8_t{77});
  renderer_->Render(Camera(), std::vector<DrawItem>{Item(kWall, {kWallX, 0, 0})},
                    frame.Buffers(Set({proto::CHANNEL_NORMALS})), {});
  EXPECT_NEAR(frame.normals[3 * frame.At(80, 60) + 2], -1.0f, 1e-4f);
  EXPECT_TRUE(std::all_of(frame.depth.begin(), frame.depth.end(), [](float d) { return d == -7.0f; }));
  EXPECT_TRUE(std::all_of(frame.flow.begin(), frame.flow.end(), [](float d) { return d == -7.0f; }));
  EXPECT_TRUE(std::all_of(frame.semantic.begin(), frame.semantic.end(), [](uint8_t s) { return s == 77; }));
}

}  // namespace
}  // namespace sim4cv::render
