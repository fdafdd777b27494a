// sim4cv::driving::WaypointModel (clients/cpp/examples/driving/): ONNX files
// written at test time by tests/python/driving_onnx_export.py (torch,
// sim4cv.driving_net.export_onnx on untrained WaypointNets) must give torch's
// outputs within 1e-4; files that break the contract are refused, naming the
// expected and the found shapes. Skipped when torch is missing.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "driving/waypoint_model.h"

namespace sim4cv::driving {
namespace {

namespace fs = std::filesystem;

// The repository root, from this file's path.
fs::path Source(const std::string& relative) {
  return fs::path(__FILE__).parent_path().parent_path().parent_path() / relative;
}

std::vector<char> ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in) << path;
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class WaypointModelTest : public ::testing::Test {
 protected:
  // One export for the whole suite (torch takes seconds to start).
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("sim4cv_driving_model_" + std::to_string(getpid())));
    const std::string command = "PYTHONPATH='" + Source("clients/python").string() + "' /usr/bin/python3 '" +
                                Source("tests/python/driving_onnx_export.py").string() + "' '" + dir_->string() +
                                "' 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    char buffer[512];
    while (pipe && std::fgets(buffer, sizeof buffer, pipe)) *output_ += buffer;
    const int status = pipe ? pclose(pipe) : -1;
    exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete dir_;
  }
  void SetUp() override {
    if (exit_status_ == 77) GTEST_SKIP() << "torch is missing, no ONNX files to test: " << *output_;
    ASSERT_EQ(exit_status_, 0) << "driving_onnx_export.py failed:\n" << *output_;
  }

  static std::string File(const std::string& name) { return (*dir_ / name).string(); }
  // An H x W x 3 uint8 RGB image the script wrote.
  static cv::Mat Image(const std::string& name, int height, int width) {
    const std::vector<char> bytes = ReadBytes(*dir_ / name);
    EXPECT_EQ(bytes.size(), static_cast<std::size_t>(height * width * 3)) << name;
    return cv::Mat(height, width, CV_8UC3, const_cast<char*>(bytes.data())).clone();
  }
  static Waypoints TorchOut(const std::string& name) {
    const std::vector<char> bytes = ReadBytes(*dir_ / name);
    Waypoints out{};
    EXPECT_EQ(bytes.size(), sizeof out) << name;
    std::memcpy(out.data(), bytes.data(), std::min(bytes.size(), sizeof out));
    return out;
  }
  static void ExpectNear(const Waypoints& got, const Waypoints& torch, const std::string& what) {
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], torch[i], 1e-4) << what << " output " << i;
  }
  // The ModelError message loading `path` gives ("accepted" if none).
  static std::string Refusal(const std::string& path) {
    try {
      WaypointModel model(path);
    } catch (const ModelError& e) {
      return e.what();
    }
    return "accepted";
  }

  static fs::path* dir_;
  static std::string* output_;
  static int exit_status_;
};

fs::path* WaypointModelTest::dir_ = nullptr;
std::string* WaypointModelTest::output_ = new std::string;
int WaypointModelTest::exit_status_ = -1;

TEST_F(WaypointModelTest, AnExportedNetGivesTorchsOutputsAtItsSize) {
  WaypointModel model(File("small.onnx"));
  EXPECT_EQ(model.width(), 160);
  EXPECT_EQ(model.height(), 90);
  EXPECT_FALSE(model.has_goal());
  const cv::Mat image = Image("small_image.bin", 90, 160);
  const Waypoints torch = TorchOut("small_out.bin");
  ExpectNear(model.Predict(image), torch, "small");
  ExpectNear(model.Predict(image, 1.0f), torch, "small, goal ignored");
  // The test can tell RGB from BGR: the swapped image gives other outputs.
  cv::Mat bgr;
  cv::cvtColor(image, bgr, cv::COLOR_RGB2BGR);
  const Waypoints swapped = model.Predict(bgr);
  double difference = 0;
  for (std::size_t i = 0; i < swapped.size(); ++i) difference += std::abs(swapped[i] - torch[i]);
  EXPECT_GT(difference, 1e-3) << "channel order makes no difference: the RGB check proves nothing";
}

TEST_F(WaypointModelTest, ALargerFrameIsShrunkWithInterArea) {
  WaypointModel model(File("small.onnx"));
  ExpectNear(model.Predict(Image("small_big_image.bin", 180, 320)), TorchOut("small_big_out.bin"), "180x320 frame");
}

TEST_F(WaypointModelTest, AGoalModelTakesTheGoal) {
  WaypointModel model(File("goal.onnx"));
  EXPECT_TRUE(model.has_goal());
  const cv::Mat image = Image("goal_image.bin", 90, 160);
  ExpectNear(model.Predict(image, -1.0f), TorchOut("goal_out_m1.bin"), "goal -1");
  ExpectNear(model.Predict(image, 0.0f), TorchOut("goal_out_0.bin"), "goal 0");
  ExpectNear(model.Predict(image, 1.0f), TorchOut("goal_out_p1.bin"), "goal +1");
}

// The weather-robust model's input normalisation (an InstanceNormalization node) runs in OpenCV's DNN too.
TEST_F(WaypointModelTest, AnImageNormalisedNetGivesTorchsOutputs) {
  WaypointModel model(File("image_norm.onnx"));
  EXPECT_TRUE(model.has_goal());
  ExpectNear(model.Predict(Image("image_norm_image.bin", 90, 160), 1.0f), TorchOut("image_norm_out.bin"),
             "image-normalised, goal +1");
}

TEST_F(WaypointModelTest, AnOutputOtherThanEightNumbersIsRefused) {
  EXPECT_EQ(Refusal(File("four_outputs.onnx")),
            "WaypointModel: '" + File("four_outputs.onnx") +
                "': output 'waypoints' is [1, 4]; expected [1, 8] (v1 h1 v2 h2 v3 h3 v4 h4)");
}

TEST_F(WaypointModelTest, AnInputOtherThanThreeChannelsIsRefused) {
  EXPECT_EQ(Refusal(File("gray_input.onnx")),
            "WaypointModel: '" + File("gray_input.onnx") +
                "': input 'image' is [1, 1, 90, 160]; expected [1, 3, H, W] (3 channels, RGB; fixed H and W)");
}

TEST_F(WaypointModelTest, AnImageThatIsNotRgbIsRefused) {
  WaypointModel model(File("small.onnx"));
  EXPECT_THROW(model.Predict(cv::Mat(90, 160, CV_8UC1, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(model.Predict(cv::Mat()), std::invalid_argument);
}

// No torch needed.
TEST(WaypointModelFiles, AMissingFileIsRefusedNamingItsPath) {
  const std::string path = "/nonexistent/sim4cv/model.onnx";
  try {
    WaypointModel model(path);
    FAIL() << "a missing file was accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()),
              "WaypointModel: cannot read the model file '" + path + "': No such file or directory");
  }
}

TEST(WaypointModelFiles, AFileThatIsNotOnnxIsRefused) {
  const fs::path path = fs::temp_directory_path() / ("sim4cv_not_onnx_" + std::to_string(getpid()) + ".onnx");
  std::ofstream(path) << "hello, this is text\n";
  try {
    WaypointModel model(path.string());
    ADD_FAILURE() << "a text file was accepted";
  } catch (const ModelError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("WaypointModel: '" + path.string() + "' is not an ONNX model", 0), 0u)
        << e.what();
  }
  fs::remove(path);
}

}  // namespace
}  // namespace sim4cv::driving
