#include "server/render/renderer.h"
#include "tests/support/rendered_frame.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/mesh_builder.h"

namespace sim4cv::render {
namespace {

constexpr uint32_t kWidth = 160;
constexpr uint32_t kHeight = 120;
constexpr MeshId kUnitCube = 0;  // half extent 0.5 m
constexpr MeshId kCar = 1;
constexpr uint32_t kUntouched = 12345;

// A frame plus unoccluded-pixel counts that start at kUntouched, to tell
// "counted as zero" from "not counted".
struct Frame : testing::RenderedFrame {
  std::array<uint32_t, 8> unoccluded;
  Frame(uint32_t w, uint32_t h) : RenderedFrame(w, h) { unoccluded.fill(kUntouched); }
};

// Looks along world +x from the origin, z up: world +y is image left.
CameraView ForwardCamera(uint32_t width = kWidth, uint32_t height = kHeight) {
  CameraView camera;
  camera.world_from_camera = LookAt({0, 0, 0}, {1, 0, 0}, {0, 0, 1});
  camera.width = width;
  camera.height = height;
  return camera;
}

DrawItem Item(MeshId mesh, const Eigen::Vector3f& position, InstanceId instance) {
  return {mesh, PoseMatrix(position, Eigen::Quaternionf::Identity()), instance};
}

class RendererTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    context_ = CreateGlContext();
    renderer_ = std::make_unique<Renderer>(
        std::vector<Mesh>{MakeBox({0.5f, 0.5f, 0.5f}, {0.8f, 0.2f, 0.1f}), MakeCarMesh(4.0f, 1.8f, 1.5f, {0.1f, 0.3f, 0.8f})},
        kWidth, kHeight);
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    context_.reset();
  }

  static Frame Render(const std::vector<DrawItem>& items, const CameraView& camera = ForwardCamera()) {
    Frame frame(camera.width, camera.height);
    renderer_->Render(camera, items, frame.Buffers(), frame.unoccluded);
    return frame;
  }

  static std::unique_ptr<GlContext> context_;
  static std::unique_ptr<Renderer> renderer_;
};

std::unique_ptr<GlContext> RendererTest::context_;
std::unique_ptr<Renderer> RendererTest::renderer_;

TEST_F(RendererTest, ContextIsNamed) { EXPECT_FALSE(context_->RendererName().empty()); }

TEST_F(RendererTest, BoxInFrontFillsTheCentreOnly) {
  const Frame frame = Render({Item(kUnitCube, {5, 0, 0}, 3)});
  const size_t centre = frame.At(kWidth / 2, kHeight / 2);
  EXPECT_EQ(frame.mask[centre], 3);
  for (size_t corner : {frame.At(0, 0), frame.At(kWidth - 1, 0), frame.At(0, kHeight - 1),
                        frame.At(kWidth - 1, kHeight - 1)}) {
    EXPECT_EQ(frame.mask[corner], kUnlabelled);
    EXPECT_EQ(frame.depth[corner], std::numeric_limits<float>::infinity());
  }
  EXPECT_NEAR(frame.depth[centre], 4.5f, 0.01f);  // the near face, not the centre of the box

  const uint8_t* centre_rgb = &frame.rgb[3 * centre];
  const uint8_t* background_rgb = &frame.rgb[0];
  EXPECT_GT(centre_rgb[0] + centre_rgb[1] + centre_rgb[2], 0);
  EXPECT_FALSE(std::equal(centre_rgb, centre_rgb + 3, background_rgb));
}

TEST_F(RendererTest, ImageIsUprightAndNotMirrored) {
  // Up in the world is up in the image; world +y is left for this camera.
  const Frame frame = Render({Item(kUnitCube, {5, 1.2f, 1.2f}, 1)});
  ASSERT_GT(frame.Count(1), 0u);
  for (uint32_t y = 0; y < kHeight; ++y) {
    for (uint32_t x = 0; x < kWidth; ++x) {
      if (frame.mask[frame.At(x, y)] != 1) continue;
      ASSERT_LT(y, kHeight / 2) << "object below the middle row";
      ASSERT_LT(x, kWidth / 2) << "object right of the middle column";
    }
  }
}

TEST_F(RendererTest, SmallerCameraThanTheFramebufferStaysUpright) {
  const CameraView camera = ForwardCamera(64, 48);
  const Frame frame = Render({Item(kUnitCube, {5, 0, 1.0f}, 1)}, camera);
  ASSERT_GT(frame.Count(1), 0u);
  EXPECT_EQ(frame.mask[frame.At(32, 10)], 1);
  EXPECT_EQ(frame.mask[frame.At(32, 40)], kUnlabelled);
}

TEST_F(RendererTest, UnoccludedCountMatchesVisibleWhenNothingOccludes) {
  const Frame frame = Render({Item(kUnitCube, {5, 0, 0}, 1)});
  EXPECT_GT(frame.Count(1), 0u);
  EXPECT_EQ(frame.unoccluded[1], frame.Count(1));
  EXPECT_EQ(frame.unoccluded[2], kUntouched);
}

TEST_F(RendererTest, OccluderHidesPartButNotTheUnoccludedCount) {
  const Frame alone = Render({Item(kUnitCube, {5, 0, 0}, 1)});
  // A cube 2 m in front, shifted left, covers the left part of cube 1.
  const Frame occluded = Render({Item(kUnitCube, {5, 0, 0}, 1), Item(kUnitCube, {3, 0.5f, 0}, 2)});
  EXPECT_EQ(occluded.unoccluded[1], alone.unoccluded[1]);
  EXPECT_LT(occluded.Count(1), alone.Count(1));
  EXPECT_GT(occluded.Count(1), 0u);
  EXPECT_GT(occluded.unoccluded[1], occluded.Count(1));
  EXPECT_EQ(occluded.unoccluded[2], occluded.Count(2));
}

TEST_F(RendererTest, ItemsSharingAnIdCountTheirUnionOnce) {
  // Two overlapping cubes with one id: any per-item sum would exceed the union.
  const Frame one = Render({Item(kUnitCube, {5, 0, 0}, 4)});
  const Frame frame = Render({Item(kUnitCube, {5, 0, 0}, 4), Item(kUnitCube, {5.5f, 0.3f, 0.3f}, 4)});
  EXPECT_GT(frame.Count(4), one.Count(4));
  EXPECT_EQ(frame.unoccluded[4], frame.Count(4));
}

TEST_F(RendererTest, NonConvexMeshIsCountedOncePerPixel) {
  CameraView camera = ForwardCamera();
  camera.world_from_camera = LookAt({-6, -5, 3}, {0, 0, 0}, {0, 0, 1});
  const Frame frame = Render({Item(kCar, {0, 0, 0}, 5)}, camera);
  EXPECT_GT(frame.Count(5), 100u);
  EXPECT_EQ(frame.unoccluded[5], frame.Count(5));
}

TEST_F(RendererTest, CountsStayExactPastTheStencilReferenceRange) {
  // 300 separate small cubes: more instances than 8-bit stencil references.
  std::vector<DrawItem> items;
  for (int row = 0; row < 15; ++row) {
    for (int column = 0; column < 20; ++column) {
      items.push_back(Item(kUnitCube, {30.0f, 1.5f * (column - 9.5f), 1.5f * (row - 7.0f)},
                           static_cast<InstanceId>(items.size() + 1)));
    }
  }
  Frame frame(kWidth, kHeight);
  std::vector<uint32_t> unoccluded(items.size() + 1, kUntouched);
  renderer_->Render(ForwardCamera(), items, frame.Buffers(), unoccluded);
  for (const DrawItem& item : items) {
    ASSERT_GT(frame.Count(item.instance), 0u) << "instance " << item.instance;
    ASSERT_EQ(unoccluded[item.instance], frame.Count(item.instance)) << "instance " << item.instance;
  }
}

TEST_F(RendererTest, SameInputGivesIdenticalBytes) {
  const std::vector<DrawItem> items = {Item(kUnitCube, {5, 0, 0}, 1), Item(kCar, {12, -3, 0}, 2),
                                       Item(kUnitCube, {3, 0.5f, 0}, 3)};
  const Frame first = Render(items);
  const Frame second = Render(items);
  EXPECT_EQ(first.rgb, second.rgb);
  EXPECT_EQ(first.depth, second.depth);
  EXPECT_EQ(first.mask, second.mask);
  EXPECT_EQ(first.unoccluded, second.unoccluded);
}

TEST_F(RendererTest, ItemOutsideTheFrustumLeavesNoTrace) {
  const Frame frame = Render({Item(kUnitCube, {-5, 0, 0}, 1), Item(kUnitCube, {5, 40, 0}, 2)});
  EXPECT_EQ(frame.Count(kUnlabelled), kWidth * kHeight);
  EXPECT_TRUE(std::all_of(frame.depth.begin(), frame.depth.end(), [](float d) { return std::isinf(d); }));
  EXPECT_EQ(frame.unoccluded[1], kUntouched);  // culled before the count, not counted as zero
  EXPECT_EQ(frame.unoccluded[2], kUntouched);
}

TEST_F(RendererTest, NullChannelsAreSkipped) {
  Frame frame(kWidth, kHeight);
  FrameBuffers mask_only{};
  mask_only[2] = reinterpret_cast<uint8_t*>(frame.mask.data());
  renderer_->Render(ForwardCamera(), std::vector<DrawItem>{Item(kUnitCube, {5, 0, 0}, 1)}, mask_only, frame.unoccluded);
  EXPECT_GT(frame.Count(1), 0u);
  EXPECT_TRUE(std::all_of(frame.rgb.begin(), frame.rgb.end(), [](uint8_t v) { return v == 0; }));
}

TEST_F(RendererTest, RejectsAnInstanceBeyondTheCountSpan) {
  Frame frame(kWidth, kHeight);
  const std::vector<DrawItem> items = {Item(kUnitCube, {5, 0, 0}, 8)};
  EXPECT_THROW(renderer_->Render(ForwardCamera(), items, frame.Buffers(), frame.unoccluded), std::invalid_argument);
}

TEST_F(RendererTest, RejectsAMeshIndexPastItsVertices) {
  Mesh broken = MakeBox({1, 1, 1}, {1, 1, 1});
  broken.indices.back() = static_cast<uint32_t>(broken.vertices.size());
  EXPECT_THROW(Renderer({broken}, 8, 8), std::invalid_argument);
}

}  // namespace
}  // namespace sim4cv::render
