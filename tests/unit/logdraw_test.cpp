// sim4cv_logdraw on synthetic logs over a shipped map: the PNG shows each
// log's UAV path in its own colour.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "server/sim/map/map_text.h"
#include "server/sim/map/road_graph.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/runlog_test_support.h"
#include "tools/log_drawing.h"

namespace sim4cv::runlog {
namespace {

using namespace testing;
const std::string kMap = std::string(SIM4CV_SOURCE_DIR) + "/scenes/tracking/easy_desert.map";
// The paper's figure: four UAVs, each driven by a different tracker.
constexpr int kLogs = 4;
const char* const kTrackers[kLogs] = {"MOSSE_CA", "SRDCF", "MEEM", "SAMF"};

// A run in which the car drives the map's loop and a UAV follows it `offset`
// metres to the side, wavering more and more, until it loses the car after
// `fraction` of the loop and drifts on for 30 m.
std::string WriteSyntheticLog(int index, double offset, double fraction) {
  const map::Map map = map::LoadMapFile(kMap);
  const map::SampledPath loop = map::RoadGraph(map).SampleRoute(*map.FindRoute("loop"), 1.0);
  RunLogHeader header = TestHeader();
  header.label = kTrackers[index];
  header.entities.pop_back();  // car and uav
  std::string name = header.label + ".s4log";
  std::transform(name.begin(), name.end(), name.begin(), [](char c) { return std::tolower(c); });
  const std::string path = TempPath(name);
  RunLogWriter writer(path, header);
  const auto frames = static_cast<std::size_t>(fraction * static_cast<double>(loop.points.size()));
  Eigen::Vector2d uav = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < frames + 30; ++i) {
    const std::size_t on_loop = std::min(i, frames - 1);
    const Eigen::Vector2d car = loop.points[on_loop];
    const double heading = loop.heading[on_loop];
    const Eigen::Vector2d forward(std::cos(heading), std::sin(heading)), left(-forward.y(), forward.x());
    const double waver = 1.5 * static_cast<double>(on_loop) / static_cast<double>(frames) * std::sin(i / 9.0);
    uav = i < frames ? Eigen::Vector2d(car + (offset + waver) * left) : Eigen::Vector2d(uav + forward);
    FrameLogRecord record;
    record.frame_id = i + 1;
    record.entities = {{1, {}}, {2, {}}};
    record.entities[0].body.position = {car.x(), car.y(), 0.7};
    record.entities[1].body.position = {uav.x(), uav.y(), 15.0};
    writer.Append(record);
  }
  return path;
}

// Runs the tool; returns its exit status.
int RunLogdraw(const std::string& arguments) {
  const std::string command = std::string(SIM4CV_LOGDRAW_PATH) + " " + arguments;
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

int CountPixels(const cv::Mat& image, std::size_t colour_index) {
  const auto& c = tools::kTrackColours[colour_index];
  cv::Mat match;
  cv::inRange(image, cv::Scalar(c[0], c[1], c[2]), cv::Scalar(c[0], c[1], c[2]), match);
  return cv::countNonZero(match);
}

class LogdrawTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const double offsets[kLogs] = {-6.0, -2.0, 2.0, 6.0};
    const double fractions[kLogs] = {1.0, 0.75, 0.5, 0.25};
    for (int i = 0; i < kLogs; ++i) {
      paths_.push_back(WriteSyntheticLog(i, offsets[i], fractions[i]));
      logs_.append(" ").append(paths_.back());
    }
  }
  std::vector<std::string> paths_;
  std::string logs_;  // the paths, each after a space
};

TEST_F(LogdrawTest, DrawsEachLogsUavInItsOwnColour) {
  const std::string png = TempPath("map.png");
  ASSERT_EQ(RunLogdraw("--map " + kMap + " --out " + png + logs_), 0);
  const cv::Mat image = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty()) << png;
  EXPECT_GE(image.cols, 800);
  int previous = 1 << 30;
  for (std::size_t i = 0; i < kLogs; ++i) {
    const int pixels = CountPixels(image, i);
    EXPECT_GT(pixels, 500) << "log " << i;  // a path hundreds of metres long, 3 px wide
    EXPECT_LT(pixels, previous) << "log " << i << " ran a shorter part of the loop";
    previous = pixels;
  }
  EXPECT_EQ(CountPixels(image, kLogs), 0);  // no colour beyond the logs'
  // To look at the drawing: SIM4CV_KEEP_DRAWING=/some/file.png ctest -R logdraw_test
  if (const char* keep = std::getenv("SIM4CV_KEEP_DRAWING")) {
    std::filesystem::copy_file(png, keep, std::filesystem::copy_options::overwrite_existing);
  }
}

TEST_F(LogdrawTest, DrawsANamedEntityAtAChosenScale) {
  const std::string png = TempPath("car.png");
  ASSERT_EQ(RunLogdraw("--map " + kMap + " --out " + png + " --entity car --scale 2 " + paths_[0]), 0);
  const cv::Mat image = cv::imread(png, cv::IMREAD_COLOR);
  ASSERT_FALSE(image.empty());
  EXPECT_LT(image.cols, 800);  // 250 m at 2 px/m, plus margins and legend room
  EXPECT_GT(CountPixels(image, 0), 200);
}

TEST_F(LogdrawTest, RefusesUnknownEntitiesAndBadArguments) {
  const std::string png = TempPath("bad.png");
  EXPECT_EQ(RunLogdraw("--map " + kMap + " --out " + png + " --entity nobody" + logs_ + " 2>/dev/null"), 1);
  EXPECT_EQ(RunLogdraw("--map " + kMap + logs_ + " 2>/dev/null"), 2);  // no --out
  EXPECT_EQ(RunLogdraw("--map " + kMap + " --out " + png + " --scale -1" + logs_ + " 2>/dev/null"), 2);
  EXPECT_EQ(RunLogdraw("--map " + kMap + " --out " + png + " /nonexistent.s4log 2>/dev/null"), 1);
}

}  // namespace
}  // namespace sim4cv::runlog
