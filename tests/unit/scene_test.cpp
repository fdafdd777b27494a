// Unit tests of the scene text format parser (server/sim/scene.*).
#include "server/sim/scene.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "tests/support/no_warnings.h"

namespace sim4cv::sim {
namespace {

// Three road points: the smallest valid loop.
const std::string kMinimalRoad = "road 0 0\nroad 10 0\nroad 10 10\n";

// Parses `text` expecting std::invalid_argument; returns its message.
std::string ParseError(const std::string& text, uint32_t width = 320, uint32_t height = 180) {
  try {
    ParseScene(text, width, height);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  ADD_FAILURE() << "no std::invalid_argument for scene text:\n" << text;
  return {};
}

// The message names the line number and the offending line text.
void ExpectNamesLine(const std::string& message, int line_number, const std::string& text) {
  EXPECT_NE(message.find("line " + std::to_string(line_number)), std::string::npos) << message;
  EXPECT_NE(message.find(text), std::string::npos) << message;
}

TEST(SceneTest, DefaultSceneParses) {
  const Scene scene = DefaultScene(640, 360);
  EXPECT_EQ(scene.name, "default");
  EXPECT_GE(scene.road_loop.size(), 3u);
  EXPECT_FLOAT_EQ(scene.ground_half_size, 150.0f);
  EXPECT_FLOAT_EQ(scene.lane_width, 4.0f);
  EXPECT_FLOAT_EQ(scene.car.cruise_speed, 6.0f);
  EXPECT_FLOAT_EQ(scene.uav.altitude, 15.0f);
  ASSERT_FALSE(scene.buildings.empty());
  for (std::size_t i = 0; i < scene.buildings.size(); ++i) {
    EXPECT_EQ(scene.buildings[i].id, kFirstBuildingId + i);
    EXPECT_GT(scene.buildings[i].height, 0.0f);
  }
  // The first building line: "building -30 0 8 10 12 0".
  EXPECT_FLOAT_EQ(scene.buildings[0].centre.x(), -30.0f);
  EXPECT_FLOAT_EQ(scene.buildings[0].half_size.y(), 10.0f);
  EXPECT_FLOAT_EQ(scene.buildings[0].height, 12.0f);
  ASSERT_EQ(scene.cameras.size(), 3u);  // uav, car_front, car_chase
  EXPECT_EQ(scene.cameras[0].name, "uav");
  EXPECT_EQ(scene.cameras[0].mounted_on, scene.uav.name);
  EXPECT_EQ(scene.cameras[0].width, 640u);
  EXPECT_EQ(scene.cameras[0].height, 360u);
  EXPECT_FLOAT_EQ(scene.cameras[0].pitch_down_deg, 60.0f);
  EXPECT_EQ(scene.FindCamera("uav"), 0);
  EXPECT_EQ(scene.FindCamera("nope"), -1);
}

TEST(SceneTest, DefaultSceneTextIsTheDefaultScene) {
  const Scene a = DefaultScene(320, 180);
  const Scene b = ParseScene(DefaultSceneText(), 320, 180);
  EXPECT_EQ(a.road_loop, b.road_loop);
  EXPECT_EQ(a.buildings.size(), b.buildings.size());
}

TEST(SceneTest, EveryKeywordIsApplied) {
  const Scene scene = ParseScene(
      "scene town\n"
      "ground 50\n"
      "lane_width 3.5\n"
      "car_speed 9\n"
      "uav_altitude 20\n"
      "camera_pitch 45\n"
      "building 1 2 3 4 5 6\n"
      "building -1 -2 1 1 1 0\n" +
          kMinimalRoad,
      100, 50);
  EXPECT_EQ(scene.name, "town");
  EXPECT_FLOAT_EQ(scene.ground_half_size, 50.0f);
  EXPECT_FLOAT_EQ(scene.lane_width, 3.5f);
  EXPECT_FLOAT_EQ(scene.car.cruise_speed, 9.0f);
  EXPECT_FLOAT_EQ(scene.uav.altitude, 20.0f);
  ASSERT_EQ(scene.cameras.size(), 3u);  // uav, car_front, car_chase
  EXPECT_FLOAT_EQ(scene.cameras[0].pitch_down_deg, 45.0f);
  EXPECT_EQ(scene.cameras[0].width, 100u);
  EXPECT_EQ(scene.cameras[0].height, 50u);
  ASSERT_EQ(scene.buildings.size(), 2u);
  EXPECT_EQ(scene.buildings[0].id, 100u);
  EXPECT_EQ(scene.buildings[1].id, 101u);
  EXPECT_EQ(scene.buildings[0].centre, Eigen::Vector2f(1, 2));
  EXPECT_EQ(scene.buildings[0].half_size, Eigen::Vector2f(3, 4));
  EXPECT_FLOAT_EQ(scene.buildings[0].height, 5.0f);
  EXPECT_FLOAT_EQ(scene.buildings[0].yaw_deg, 6.0f);
  ASSERT_EQ(scene.road_loop.size(), 3u);
  EXPECT_EQ(scene.road_loop[1], Eigen::Vector2f(10, 0));
}

TEST(SceneTest, CommentsAndBlankLinesAreIgnored) {
  const Scene scene = ParseScene(
      "# a comment line\n"
      "\n"
      "   \t  \n"
      "scene commented   # trailing comment\n"
      "road 0 0 # first\n"
      "   # indented comment\n"
      "road 10 0\n"
      "\n"
      "road 10 10#no space before the hash\n",
      320, 180);
  EXPECT_EQ(scene.name, "commented");
  ASSERT_EQ(scene.road_loop.size(), 3u);
  EXPECT_EQ(scene.road_loop[2], Eigen::Vector2f(10, 10));
}

TEST(SceneTest, UnknownKeywordNamesLineAndKeyword) {
  const std::string message = ParseError(kMinimalRoad + "\nbulding 1 2 3 4 5 6\n");
  ExpectNamesLine(message, 5, "bulding");
}

TEST(SceneTest, WrongNumberCountNamesLineAndText) {
  ExpectNamesLine(ParseError("road 1\n" + kMinimalRoad), 1, "road 1");
  ExpectNamesLine(ParseError(kMinimalRoad + "road 1 2 3\n"), 4, "road 1 2 3");
  ExpectNamesLine(ParseError(kMinimalRoad + "building 1 2 3 4 5\n"), 4, "building 1 2 3 4 5");
  ExpectNamesLine(ParseError("ground\n" + kMinimalRoad), 1, "ground");
  ExpectNamesLine(ParseError("# c\nroad 1 two\n" + kMinimalRoad), 2, "road 1 two");
  const std::string message = ParseError("lane_width 3 4\n" + kMinimalRoad);
  ExpectNamesLine(message, 1, "lane_width 3 4");
  EXPECT_NE(message.find("expected 1 numbers"), std::string::npos) << message;
}

TEST(SceneTest, NonFiniteNumberIsRefused) {
  // Whatever the reason given (the stream refuses "nan" and "inf" as numbers,
  // an overflowing literal is out of range), the line must be named.
  ExpectNamesLine(ParseError("car_speed nan\n" + kMinimalRoad), 1, "car_speed nan");
  ExpectNamesLine(ParseError(kMinimalRoad + "road inf 0\n"), 4, "road inf 0");
  ExpectNamesLine(ParseError(kMinimalRoad + "road 1e999 0\n"), 4, "road 1e999 0");
}

// BUG: docs/scenes.md documents "scene line N 'LINE': number not finite" for
// an infinite or NaN value, but ReadNumbers (server/sim/scene.cpp) reads with
// `words >> float`, which never yields inf/NaN: "inf"/"nan" fail to parse and
// "1e999" overflows (failbit), so the message is always "expected K numbers"
// and the std::isfinite check is unreachable. Either the parser should accept
// and then refuse them by name, or the doc's table should drop the line.
TEST(SceneTest, NonFiniteNumberMessageSaysNotFinite) {
  EXPECT_NE(ParseError("car_speed inf\n" + kMinimalRoad).find("number not finite"), std::string::npos);
  EXPECT_NE(ParseError(kMinimalRoad + "road 1e999 0\n").find("number not finite"), std::string::npos);
}

TEST(SceneTest, NegativeOrZeroSizesAreRefused) {
  ExpectNamesLine(ParseError(kMinimalRoad + "building 0 0 -1 2 3 0\n"), 4, "building 0 0 -1 2 3 0");
  ExpectNamesLine(ParseError(kMinimalRoad + "building 0 0 1 -2 3 0\n"), 4, "building 0 0 1 -2 3 0");
  ExpectNamesLine(ParseError(kMinimalRoad + "building 0 0 1 2 0 0\n"), 4, "building 0 0 1 2 0 0");
  ExpectNamesLine(ParseError("ground -5\n" + kMinimalRoad), 1, "ground -5");
  ExpectNamesLine(ParseError("lane_width 0\n" + kMinimalRoad), 1, "lane_width 0");
  ExpectNamesLine(ParseError("car_speed -1\n" + kMinimalRoad), 1, "car_speed -1");
  const std::string message = ParseError("\nuav_altitude -3\n" + kMinimalRoad);
  ExpectNamesLine(message, 2, "uav_altitude -3");
  EXPECT_NE(message.find("must be > 0"), std::string::npos) << message;
}

TEST(SceneTest, CameraPitchOutOfRangeIsRefused) {
  ExpectNamesLine(ParseError("camera_pitch 0\n" + kMinimalRoad), 1, "camera_pitch 0");
  ExpectNamesLine(ParseError("camera_pitch -10\n" + kMinimalRoad), 1, "camera_pitch -10");
  const std::string message = ParseError("camera_pitch 90.5\n" + kMinimalRoad);
  ExpectNamesLine(message, 1, "camera_pitch 90.5");
  EXPECT_NE(message.find("(0, 90]"), std::string::npos) << message;
  // The bounds themselves: 90 is allowed.
  EXPECT_FLOAT_EQ(ParseScene("camera_pitch 90\n" + kMinimalRoad, 320, 180).cameras[0].pitch_down_deg, 90.0f);
}

TEST(SceneTest, FewerThanThreeRoadPointsIsRefused) {
  const std::string message = ParseError("scene short\nroad 0 0\nroad 1 0\n");
  EXPECT_NE(message.find("2 road points"), std::string::npos) << message;
  EXPECT_NE(message.find("at least 3"), std::string::npos) << message;
  EXPECT_NE(message.find("short"), std::string::npos) << message;
  EXPECT_NE(ParseError("").find("0 road points"), std::string::npos);
}

TEST(SceneTest, ZeroCameraSizeIsRefused) {
  EXPECT_NE(ParseError(kMinimalRoad, 0, 180).find("0x180"), std::string::npos);
  EXPECT_NE(ParseError(kMinimalRoad, 320, 0).find("320x0"), std::string::npos);
}

TEST(SceneTest, SceneWithoutNameIsRefused) {
  const std::string message = ParseError("scene\n" + kMinimalRoad);
  EXPECT_NE(message.find("line 1"), std::string::npos) << message;
}

TEST(SceneTest, LoadSceneFileNamesMissingFile) {
  try {
    LoadSceneFile("/nonexistent/dir/x.scene", 320, 180);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/x.scene"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace sim4cv::sim
