// The camera model sent with every frame (server/render/projection.*):
// intrinsics, the OpenCV-convention pose, 3D boxes projected into the image,
// and agreement of all three with what the renderer draws.
#include "server/render/projection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "server/render/camera_math.h"
#include "server/render/gl_context.h"
#include "server/render/ground_truth.h"
#include "server/render/mesh_builder.h"
#include "server/render/renderer.h"
#include "tests/support/rendered_frame.h"

namespace sim4cv::render {
namespace {

constexpr uint32_t kWidth = 320;
constexpr uint32_t kHeight = 180;

// At the origin looking along world +x, z up: world +y is image left, +z image up.
CameraView ForwardCamera() {
  CameraView view;
  view.world_from_camera = LookAt({0, 0, 0}, {1, 0, 0}, {0, 0, 1});
  view.fov_y_deg = 60.0f;
  view.width = kWidth;
  view.height = kHeight;
  return view;
}

const Eigen::Quaterniond kNoTurn = Eigen::Quaterniond::Identity();

void ExpectRect(const ImageRect& rect, double x0, double y0, double x1, double y1, double tolerance = 1e-3) {
  EXPECT_NEAR(rect.x, x0, tolerance);
  EXPECT_NEAR(rect.y, y0, tolerance);
  EXPECT_NEAR(rect.x + rect.width, x1, tolerance);
  EXPECT_NEAR(rect.y + rect.height, y1, tolerance);
}

TEST(Intrinsics, FollowTheFieldOfViewAndTheImageCentre) {
  const CameraIntrinsics k = IntrinsicsOf(ForwardCamera());
  const double expected = 90.0 / std::tan(30.0 * std::numbers::pi / 180.0);  // docs/protocol.md: 155.88 at 320x180
  EXPECT_NEAR(k.fx, expected, 1e-9);
  EXPECT_NEAR(k.fy, expected, 1e-9);
  EXPECT_NEAR(k.fx, 155.88, 0.01);
  EXPECT_DOUBLE_EQ(k.cx, 160.0);
  EXPECT_DOUBLE_EQ(k.cy, 90.0);
  EXPECT_EQ(k.width, kWidth);
  EXPECT_EQ(k.height, kHeight);
}

TEST(OpenCvPose, AxesAreRightDownForward) {
  CameraView view = ForwardCamera();
  view.world_from_camera = LookAt({1, 2, 10}, {1, 12, 10}, {0, 0, 1});  // looking north from 10 m up
  const Pose pose = OpenCvPoseOf(view);
  EXPECT_LT((pose.position - Eigen::Vector3d(1, 2, 10)).norm(), 1e-6);
  EXPECT_NEAR(pose.orientation.norm(), 1.0, 1e-12);
  EXPECT_LT((pose.orientation * Eigen::Vector3d::UnitX() - Eigen::Vector3d(1, 0, 0)).norm(), 1e-6);   // east is right
  EXPECT_LT((pose.orientation * Eigen::Vector3d::UnitY() - Eigen::Vector3d(0, 0, -1)).norm(), 1e-6);  // down
  EXPECT_LT((pose.orientation * Eigen::Vector3d::UnitZ() - Eigen::Vector3d(0, 1, 0)).norm(), 1e-6);   // north ahead
}

TEST(BoxProjector, BoxStraightAheadProjectsSymmetrically) {
  const BoxProjector camera(ForwardCamera());
  const double f = camera.intrinsics().fx;
  // Its near face (x = 9 m: 4 m wide, 2 m tall) is the widest part of the image.
  const ImageRect rect = camera.Project({10, 0, 0}, kNoTurn, {1, 2, 1});
  ExpectRect(rect, 160 - f * 2 / 9, 90 - f / 9, 160 + f * 2 / 9, 90 + f / 9);
}

TEST(BoxProjector, TurningTheBoxTurnsItsExtents) {
  const BoxProjector camera(ForwardCamera());
  const Eigen::Quaterniond quarter_turn(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()));
  const ImageRect turned = camera.Project({10, 0, 0}, quarter_turn, {2, 1, 1});
  const ImageRect straight = camera.Project({10, 0, 0}, kNoTurn, {1, 2, 1});
  ExpectRect(turned, straight.x, straight.y, straight.x + straight.width, straight.y + straight.height);
}

TEST(BoxProjector, OffCentreBoxLandsWhereThePinholeModelSays) {
  const BoxProjector camera(ForwardCamera());
  const double f = camera.intrinsics().fx;
  // A box up and to the left (world +y, +z); OpenCV camera x = -y, y = -z.
  const ImageRect rect = camera.Project({20, 3, 2}, kNoTurn, {0.5, 0.5, 0.5});
  ExpectRect(rect, 160 - f * 3.5 / 19.5, 90 - f * 2.5 / 19.5, 160 - f * 2.5 / 20.5, 90 - f * 1.5 / 20.5);
}

TEST(BoxProjector, BoxBehindTheCameraIsNotInView) {
  const BoxProjector camera(ForwardCamera());
  EXPECT_TRUE(camera.Project({-10, 0, 0}, kNoTurn, {1, 1, 1}).empty());
  EXPECT_TRUE(camera.Project({-1.05, 0, 0}, kNoTurn, {1, 1, 1}).empty()) << "nearest corner at -0.05 m";
}

TEST(BoxProjector, BoxBeyondTheFarPlaneIsNotInView) {
  const BoxProjector camera(ForwardCamera());
  EXPECT_TRUE(camera.Project({1100, 0, 0}, kNoTurn, {10, 10, 10}).empty());
  EXPECT_FALSE(camera.Project({1005, 0, 0}, kNoTurn, {10, 10, 10}).empty()) << "straddles the far plane";
}

TEST(BoxProjector, BoxBesideTheViewIsNotInView) {
  const BoxProjector camera(ForwardCamera());
  EXPECT_TRUE(camera.Project({10, 30, 0}, kNoTurn, {1, 1, 1}).empty());  // far to the left
  EXPECT_TRUE(camera.Project({10, 0, -30}, kNoTurn, {1, 1, 1}).empty());  // far below
}

TEST(BoxProjector, CornersBehindTheCameraAreClippedAtTheNearPlane) {
  const BoxProjector camera(ForwardCamera());
  const double f = camera.intrinsics().fx;
  // A thin rod through the camera along its axis: its widest visible cross
  // section is where it crosses the near plane (0.1 m). Projecting the
  // corners behind the camera would give a tiny, mirrored box instead.
  const ImageRect rect = camera.Project({0, 0, 0}, kNoTurn, {5, 0.01, 0.01});
  ExpectRect(rect, 160 - f * 0.1, 90 - f * 0.1, 160 + f * 0.1, 90 + f * 0.1);
}

TEST(BoxProjector, PartlyOutsideTheImageIsClippedToIt) {
  const BoxProjector camera(ForwardCamera());
  const double f = camera.intrinsics().fx;
  // Reaches from the centre far beyond the image's right edge (world -y).
  const ImageRect rect = camera.Project({10, -10, 0}, kNoTurn, {0.5, 10, 0.5});
  ExpectRect(rect, 160, 90 - f * 0.5 / 9.5, kWidth, 90 + f * 0.5 / 9.5);
  // A box around the camera fills the whole image.
  ExpectRect(camera.Project({0, 0, 0}, kNoTurn, {3, 3, 3}), 0, 0, kWidth, kHeight);
}

TEST(BoxProjector, ToPixelAgreesWithTheRenderersProjection) {
  CameraView view = ForwardCamera();
  view.world_from_camera = LookAt({3, -4, 12}, {10, 5, 0}, {0, 0, 1});  // oblique, looking down
  const BoxProjector camera(view);
  const Pose pose = OpenCvPoseOf(view);
  const Eigen::Matrix4f clip_from_world =
      Perspective(view.fov_y_deg, static_cast<float>(kWidth) / kHeight, view.near_m, view.far_m) *
      RigidInverse(view.world_from_camera);
  for (const Eigen::Vector3d& world :
       {Eigen::Vector3d(10, 5, 0), Eigen::Vector3d(8, 2, 1), Eigen::Vector3d(12, 9, -2)}) {
    const Eigen::Vector4f clip = clip_from_world * Eigen::Vector4f(world.x(), world.y(), world.z(), 1);
    // GL's y points up; the image's rows go down.
    const Eigen::Vector2d expected((clip.x() / clip.w() + 1) * kWidth / 2, (1 - clip.y() / clip.w()) * kHeight / 2);
    const Eigen::Vector2d pixel = camera.ToPixel(pose.orientation.inverse() * (world - pose.position));
    EXPECT_LT((pixel - expected).norm(), 1e-3) << world.transpose();
  }
}

// The projected box of an unoccluded box mesh is its silhouette's bounding
// box: the rendered tight box lies inside it and reaches within a pixel of it.
TEST(BoxProjector, MatchesTheRenderedSilhouette) {
  auto context = CreateGlContext();
  const Eigen::Vector3d half(1.5, 0.8, 0.6);
  Renderer renderer({MakeBox(half.cast<float>(), {0.8f, 0.2f, 0.1f})}, kWidth, kHeight);
  CameraView view = ForwardCamera();
  view.world_from_camera = LookAt({-6, -3, 5}, {1, 0.5, 0}, {0, 0, 1});
  const Eigen::Vector3d centre(1, 0.5, 0.4);
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  const DrawItem item{0, PoseMatrix(centre.cast<float>(), yaw.cast<float>()), 5};
  testing::RenderedFrame frame(kWidth, kHeight);
  const std::vector<uint16_t>& mask = frame.mask;
  std::vector<uint32_t> unoccluded(8);
  renderer.Render(view, std::span(&item, 1), frame.Buffers(), unoccluded);
  BoxExtractor extractor;
  std::vector<GroundTruthBox> boxes;
  const LabelledObject object{5, 1, unoccluded[5]};
  extractor.Extract(mask.data(), kWidth, kHeight, std::span(&object, 1), boxes);
  ASSERT_EQ(boxes.size(), 1u);

  const ImageRect rect = BoxProjector(view).Project(centre, yaw, half);
  const GroundTruthBox& seen = boxes[0];
  SCOPED_TRACE(::testing::Message() << "seen " << seen.x << "," << seen.y << " " << seen.width << "x" << seen.height
                                    << ", projected " << rect.x << "," << rect.y << " " << rect.width << "x"
                                    << rect.height);
  EXPECT_NEAR(seen.x, rect.x, 1.0);
  EXPECT_NEAR(seen.y, rect.y, 1.0);
  EXPECT_NEAR(seen.x + seen.width, rect.x + rect.width, 1.0);
  EXPECT_NEAR(seen.y + seen.height, rect.y + rect.height, 1.0);
}

}  // namespace
}  // namespace sim4cv::render
