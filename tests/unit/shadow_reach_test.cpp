// Which moving shadow casters the renderer may leave out of a view's shadow map
// (server/render/shadow_map.h, ShadowCanReach): only those whose shadow cannot
// fall inside the view, and none when the sun is at the horizon.
#include <gtest/gtest.h>

#include "server/render/camera_math.h"
#include "server/render/shadow_map.h"

namespace sim4cv::render {
namespace {

// A camera 20 m above the origin looking straight down (90 deg field of view,
// square image): it sees the ground from -20 to 20 m in x and y.
std::array<Eigen::Vector4f, 6> TopDownView() {
  const Eigen::Matrix4f world_from_camera = LookAt({0, 0, 20}, {0, 0, 0}, {0, 1, 0});
  return FrustumPlanes(Perspective(90.0f, 1.0f, 0.1f, 100.0f) * RigidInverse(world_from_camera));
}

// The sun in the east (+x), `elevation_deg` above the horizon.
Eigen::Vector3f SunInTheEast(float elevation_deg) {
  const float e = elevation_deg * 3.14159265f / 180.0f;
  return {std::cos(e), 0.0f, std::sin(e)};
}

TEST(ShadowReachTest, ACasterInViewCastsIntoIt) {
  EXPECT_TRUE(ShadowCanReach({0, 0, 1}, 1.0f, SunInTheEast(45), TopDownView()));
}

TEST(ShadowReachTest, ACasterOutOfViewOnTheSunsSideCastsIntoIt) {
  // 4 m east of the view's edge, 10 m high: at 45 degrees its shadow reaches 10 m further west.
  EXPECT_TRUE(ShadowCanReach({24, 0, 10}, 1.0f, SunInTheEast(45), TopDownView()));
}

TEST(ShadowReachTest, ACasterOutOfViewAwayFromTheSunDoesNot) {
  // West of the view: its shadow falls further west.
  EXPECT_FALSE(ShadowCanReach({-24, 0, 10}, 1.0f, SunInTheEast(45), TopDownView()));
  // North of it, the sun in the east: the shadow runs west, parallel to the view's edge.
  EXPECT_FALSE(ShadowCanReach({0, 30, 1}, 1.0f, SunInTheEast(45), TopDownView()));
  // East of it but low: at 45 degrees the shadow of a 1 m high caster ends far short of the view.
  EXPECT_FALSE(ShadowCanReach({50, 0, 1}, 1.0f, SunInTheEast(45), TopDownView()));
}

TEST(ShadowReachTest, TheMarginKeepsACasterJustOutsideItsOwnSphere) {
  // West of the view, the sphere's surface 0.2 m outside its side plane (the centre
  // 1.2 m): within the margin, so kept.
  EXPECT_TRUE(ShadowCanReach({-20.7f, 0, 1}, 1.0f, SunInTheEast(45), TopDownView()));
  EXPECT_FALSE(ShadowCanReach({-21.7f, 0, 1}, 1.0f, SunInTheEast(45), TopDownView()));
}

TEST(ShadowReachTest, ASunAtTheHorizonKeepsEveryCaster) {
  EXPECT_TRUE(ShadowCanReach({-500, 0, 1}, 1.0f, SunInTheEast(0.5f), TopDownView()));
}

}  // namespace
}  // namespace sim4cv::render
