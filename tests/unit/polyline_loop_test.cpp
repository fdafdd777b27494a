// Unit tests of Polyline as a closed loop and OffsetLoop (server/sim/vehicles/polyline.*) on a 10 m square.
#include "server/sim/vehicles/polyline.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>

#include "tests/support/no_warnings.h"

namespace sim4cv::vehicles {
namespace {

using Eigen::Vector2d;

constexpr double kTol = 1e-9;

// Counter-clockwise 10 m square: (0,0) -> (10,0) -> (10,10) -> (0,10).
std::vector<Vector2d> Square() { return {{0, 0}, {10, 0}, {10, 10}, {0, 10}}; }

void ExpectNear(const Vector2d& actual, const Vector2d& expected, double tol = kTol) {
  EXPECT_NEAR(actual.x(), expected.x(), tol) << "actual " << actual.transpose() << " expected " << expected.transpose();
  EXPECT_NEAR(actual.y(), expected.y(), tol) << "actual " << actual.transpose() << " expected " << expected.transpose();
}

std::string ConstructionError(std::vector<Vector2d> points) {
  try {
    Polyline path(std::move(points), true);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument";
  return {};
}

TEST(LoopTest, LengthAndPoints) {
  const Polyline path(Square(), true);
  EXPECT_NEAR(path.length(), 40.0, kTol);
  ASSERT_EQ(path.points().size(), 4u);
  ExpectNear(path.points()[2], {10, 10});
}

TEST(LoopTest, PointAtWithinTheLoop) {
  const Polyline path(Square(), true);
  ExpectNear(path.PointAt(0), {0, 0});
  ExpectNear(path.PointAt(5), {5, 0});
  ExpectNear(path.PointAt(10), {10, 0});
  ExpectNear(path.PointAt(15), {10, 5});
  ExpectNear(path.PointAt(22.5), {7.5, 10});
  ExpectNear(path.PointAt(35), {0, 5});
  ExpectNear(path.PointAt(39.999), {0, 0.001}, 1e-6);
}

TEST(LoopTest, PointAtWraps) {
  const Polyline path(Square(), true);
  ExpectNear(path.PointAt(40), {0, 0});
  ExpectNear(path.PointAt(45), {5, 0});
  ExpectNear(path.PointAt(40 * 3 + 15), {10, 5});
  ExpectNear(path.PointAt(-5), {0, 5});
  ExpectNear(path.PointAt(-40), {0, 0});
  ExpectNear(path.PointAt(-40 * 2 - 12.5), {2.5, 10});
}

TEST(LoopTest, TangentAt) {
  const Polyline path(Square(), true);
  ExpectNear(path.TangentAt(5), {1, 0});
  ExpectNear(path.TangentAt(15), {0, 1});
  ExpectNear(path.TangentAt(25), {-1, 0});
  ExpectNear(path.TangentAt(35), {0, -1});
  ExpectNear(path.TangentAt(-5), {0, -1});
  ExpectNear(path.TangentAt(40 + 15), {0, 1});
  EXPECT_NEAR(path.TangentAt(12.3).norm(), 1.0, kTol);
}

TEST(LoopTest, ProjectOntoEachSide) {
  const Polyline path(Square(), true);
  struct Case {
    Vector2d p;
    std::size_t segment;
    double arc_length;
    Vector2d point;
  };
  const Case cases[] = {
      {{3, -2}, 0, 3, {3, 0}},      // below the bottom side
      {{4, 1}, 0, 4, {4, 0}},       // inside, nearest the bottom side
      {{12, 6}, 1, 16, {10, 6}},    // right of the right side
      {{7, 11}, 2, 23, {7, 10}},    // above the top side
      {{-3, 2}, 3, 38, {0, 2}},     // left of the left side
      {{1, 8}, 3, 32, {0, 8}},      // inside, nearest the left side
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(::testing::Message() << "p = " << c.p.transpose());
    const auto projection = path.Project(c.p);
    EXPECT_NEAR(projection.arc_length, c.arc_length, kTol);
    ExpectNear(projection.point, c.point);
    ExpectNear(path.PointAt(projection.arc_length), projection.point);
  }
}

TEST(LoopTest, ProjectOutsideACornerLandsOnTheCorner) {
  const Polyline path(Square(), true);
  const auto projection = path.Project({13, 14});
  ExpectNear(projection.point, {10, 10});
  EXPECT_NEAR(projection.arc_length, 20.0, kTol);
}

TEST(LoopTest, OffsetToTheRightOfACounterClockwiseLoopMovesOutward) {
  const double offset = 2.0;
  const Polyline shifted = Polyline(OffsetLoop(Square(), offset), true);
  const Vector2d centre(5, 5);
  // Midpoints of each side of the original square are 5 m from the centre;
  // the shifted loop's sides are 5 + offset away.
  for (double s : {5.0, 15.0, 25.0, 35.0}) {
    const Polyline original(Square(), true);
    const Vector2d midpoint = original.PointAt(s);
    const auto projection = shifted.Project(midpoint);
    EXPECT_NEAR((projection.point - midpoint).norm(), offset, 1e-9) << "side midpoint " << midpoint.transpose();
    EXPECT_NEAR((projection.point - centre).norm(), 5.0 + offset, 1e-9);
  }
  // Corners move along the bisector, so the sides stay parallel: (−2,−2) etc.
  ExpectNear(shifted.points()[0], {-2, -2});
  ExpectNear(shifted.points()[1], {12, -2});
  ExpectNear(shifted.points()[2], {12, 12});
  ExpectNear(shifted.points()[3], {-2, 12});
  EXPECT_NEAR(shifted.length(), 4 * (10 + 2 * offset), 1e-9);
}

TEST(LoopTest, NegativeOffsetMovesInward) {
  const Polyline shifted = Polyline(OffsetLoop(Square(), -1.0), true);
  ExpectNear(shifted.points()[0], {1, 1});
  ExpectNear(shifted.points()[2], {9, 9});
  EXPECT_NEAR(shifted.length(), 32.0, 1e-9);
}

TEST(LoopTest, OffsetOfAClockwiseLoopMovesInward) {
  std::vector<Vector2d> clockwise = Square();
  std::reverse(clockwise.begin(), clockwise.end());
  const Polyline shifted = Polyline(OffsetLoop(clockwise, 1.0), true);
  EXPECT_NEAR(shifted.length(), 32.0, 1e-9);
}

TEST(LoopTest, RejectsFewerThanThreePoints) {
  const std::string message = ConstructionError({{0, 0}, {1, 0}});
  EXPECT_NE(message.find("at least 3 points"), std::string::npos) << message;
  EXPECT_NE(message.find("got 2"), std::string::npos) << message;
  EXPECT_NE(ConstructionError({}).find("got 0"), std::string::npos);
  try {
    OffsetLoop({{0, 0}, {1, 0}}, 1.0);
    ADD_FAILURE() << "Offset accepted 2 points";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3 points"), std::string::npos) << e.what();
  }
}

TEST(LoopTest, RejectsCoincidentPoints) {
  const std::string message = ConstructionError({{0, 0}, {1, 0}, {1, 0}, {0, 1}});
  EXPECT_NE(message.find("points 1 and 2 coincide"), std::string::npos) << message;
  // The closing segment: the last point equals the first.
  const std::string closing = ConstructionError({{0, 0}, {1, 0}, {0, 1}, {0, 0}});
  EXPECT_NE(closing.find("points 3 and 0 coincide"), std::string::npos) << closing;
}

}  // namespace
}  // namespace sim4cv::vehicles
