// sim4cv::driving::ReadModelCard (clients/cpp/examples/driving/model_card.h):
// the shipped model's card gives sim4cv_drive the settings the model was
// selected with, as sim4cv.driving_card gives them to evaluate; a card that
// is malformed or describes another network is refused, naming the file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "driving/model_card.h"

namespace sim4cv::driving {
namespace {

namespace fs = std::filesystem;

fs::path Source(const std::string& relative) {
  return fs::path(__FILE__).parent_path().parent_path().parent_path() / relative;
}

class ModelCardTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("sim4cv_model_card_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void WriteCard(const std::string& controller) {
    std::ofstream(dir_ / "model.json") << R"({"format": "sim4cv driving model card 1", "input": )"
                                          R"({"height": 90, "width": 160, "goal": true}, "controller": )"
                                       << controller << "}";
  }
  std::string Model() const { return (dir_ / "model.onnx").string(); }
  fs::path dir_;
};

TEST_F(ModelCardTest, TheShippedCardHoldsTheSelectedControllerSettings) {
  const auto card = ReadModelCard(Source("models/driving/model.onnx").string());
  ASSERT_TRUE(card.has_value());
  EXPECT_EQ(card->steer_waypoint, 2);
  EXPECT_DOUBLE_EQ(card->steer_gain.value(), 0.9);
  EXPECT_DOUBLE_EQ(card->speed_m_s.value(), 8.0);
  EXPECT_DOUBLE_EQ(card->turn_slowdown.value(), 0.5);
  EXPECT_DOUBLE_EQ(card->bend_correction.value(), 0.2);
  EXPECT_DOUBLE_EQ(card->bend_limit_m.value(), 1.5);
  EXPECT_NO_THROW(card->CheckModel(90, 160, true));
}

TEST_F(ModelCardTest, NoCardIsNoSettings) { EXPECT_FALSE(ReadModelCard(Model()).has_value()); }

TEST_F(ModelCardTest, ACardOfAnotherNetworkIsRefused) {
  WriteCard("{}");
  const auto card = ReadModelCard(Model());
  ASSERT_TRUE(card.has_value());
  EXPECT_FALSE(card->steer_waypoint.has_value());
  try {
    card->CheckModel(180, 320, false);
    FAIL() << "a 320x180 model passed a 160x90 card";
  } catch (const CardError& e) {
    EXPECT_NE(std::string(e.what()).find("describes a 160x90 network with a goal input, but the model is a 320x180 network"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(ModelCardTest, BadSettingsAndBadJsonAreRefusedNamingTheFile) {
  const auto refusal = [&](const std::string& controller) {
    WriteCard(controller);
    try {
      ReadModelCard(Model());
    } catch (const CardError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(refusal(R"({"steer_waypoint": 5})").find("controller setting \"steer_waypoint\" has a bad value 5"),
            std::string::npos);
  EXPECT_NE(refusal(R"({"steer_gain": -1})").find("\"steer_gain\" has a bad value -1"), std::string::npos);
  EXPECT_NE(refusal(R"({"bend_correction": 2})").find("\"bend_correction\" has a bad value 2"), std::string::npos);
  EXPECT_NE(refusal(R"({"bend_limit_m": 0})").find("\"bend_limit_m\" has a bad value 0"), std::string::npos);
  EXPECT_NE(refusal(R"({"steering_gain": 1})").find("unknown controller setting \"steering_gain\""),
            std::string::npos);
  EXPECT_NE(refusal("[").find((dir_ / "model.json").string() + " is not readable JSON"), std::string::npos);
}

}  // namespace
}  // namespace sim4cv::driving
