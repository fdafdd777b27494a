// Conditions against the real daemon: --conditions/--hour/--quality and
// Configure.set_conditions change RGB only; the same state renders the same
// depth, mask and boxes in every preset; bad names and hours are refused
// naming the value and the choices.
#include <cstring>

#include "tests/integration/run_to_exit.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

class ConditionsTest : public ConfigureTest {};

std::string Plane(const proto::Frame& frame, proto::Channel channel) {
  const auto image = FindImage(frame, channel);
  return std::string(reinterpret_cast<const char*>(image->data), std::size_t{image->stride} * image->height);
}

double MeanRgb(const proto::Frame& frame) {
  double sum = 0;
  const std::string rgb = Plane(frame, proto::CHANNEL_RGB);
  for (const char byte : rgb) sum += static_cast<uint8_t>(byte);
  return sum / static_cast<double>(rgb.size());
}

TEST_F(ConditionsTest, FlagsSetTheLookAndGetWorldReportsIt) {
  StartDaemon({"--conditions", "fog", "--hour", "9.5", "--quality", "fast"});
  const proto::WorldInfo world = Connect("look")->GetWorld();
  EXPECT_EQ(world.conditions().preset(), "fog");
  EXPECT_EQ(world.conditions().hour(), 9.5);
  EXPECT_EQ(world.conditions().quality(), "fast");
}

TEST_F(ConditionsTest, NightChangesRgbAndNothingElse) {
  StartDaemon();
  const auto client = Connect("look");
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  const proto::Frame noon = StepFrames(*client, 10);
  const std::string noon_depth = Plane(noon, proto::CHANNEL_DEPTH), noon_mask = Plane(noon, proto::CHANNEL_MASK),
                    noon_semantic = Plane(noon, proto::CHANNEL_SEMANTIC);
  const double noon_rgb = MeanRgb(noon);

  client->Reset();
  const proto::WorldInfo world = client->SetConditions("night");
  EXPECT_EQ(world.conditions().preset(), "night");
  const proto::Frame night = StepFrames(*client, 10);
  ASSERT_EQ(night.frame_id(), noon.frame_id()) << "the same frame of the same run";
  EXPECT_EQ(Plane(night, proto::CHANNEL_DEPTH), noon_depth);
  EXPECT_EQ(Plane(night, proto::CHANNEL_MASK), noon_mask);
  EXPECT_EQ(Plane(night, proto::CHANNEL_SEMANTIC), noon_semantic);
  ASSERT_EQ(night.boxes_size(), noon.boxes_size());
  for (int i = 0; i < noon.boxes_size(); ++i) EXPECT_EQ(night.boxes(i).SerializeAsString(), noon.boxes(i).SerializeAsString());
  EXPECT_LT(MeanRgb(night), 0.6 * noon_rgb);
}

TEST_F(ConditionsTest, BadPresetHourAndQualityAreRefusedAndTheConnectionStays) {
  StartDaemon();
  const auto client = Connect("look");
  ExpectRefused([&] { client->SetConditions("blizzard"); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SetConditions.preset 'blizzard' is not a preset", "clear_noon", "night"});
  ExpectRefused([&] { client->SetConditions("", 30.0); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SetConditions.hour is 30", "[0, 24]"});
  ExpectRefused([&] { client->SetConditions("", std::nullopt, "best"); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SetConditions.quality 'best' is not a quality"});
  EXPECT_EQ(client->GetWorld().conditions().preset(), "clear_noon") << "nothing changed";
  EXPECT_EQ(client->SetConditions("", 18.0).conditions().hour(), 18.0);
}

// Two daemons with the same randomisation seed render the same images frame
// for frame while the conditions change every 4 frames.
TEST_F(ConditionsTest, RandomisedRunsRepeatFromTheirSeed) {
  const std::vector<std::string> args = {"--randomize", "77", "--randomize-every", "4"};
  std::vector<std::string> first;
  for (int run = 0; run < 2; ++run) {
    StartDaemon(args);
    const auto client = Connect("randomised");
    const proto::WorldInfo world = client->GetWorld();
    EXPECT_EQ(world.conditions().randomize_seed(), 77u);
    EXPECT_EQ(world.conditions().randomize_every_frames(), 4u);
    EXPECT_NE(world.conditions().variation(), 0u);
    client->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
    for (int i = 0; i < 12; ++i) {
      const std::string rgb = Plane(client->StepAndReceive(), proto::CHANNEL_RGB);
      if (run == 0) {
        first.push_back(rgb);
      } else {
        EXPECT_EQ(rgb, first[static_cast<std::size_t>(i)]) << "frame " << i + 1;
      }
    }
    daemon_.reset();
  }
  EXPECT_NE(first[1], first[9]) << "new conditions every 4 frames";
}

TEST(ConditionsFlagsTest, BadFlagsStopTheDaemonNamingTheValue) {
  const auto [status, err] = RunToExit({"--conditions", "snow"});
  EXPECT_NE(status, 0);
  EXPECT_NE(err.find("--conditions 'snow' is not a preset; use one of clear_noon"), std::string::npos) << err;
  const auto [hour_status, hour_err] = RunToExit({"--hour", "-3"});
  EXPECT_NE(hour_status, 0);
  EXPECT_NE(hour_err.find("--hour is -3"), std::string::npos) << hour_err;
  const auto [every_status, every_err] = RunToExit({"--randomize-every", "10"});
  EXPECT_NE(every_status, 0);
  EXPECT_NE(every_err.find("--randomize-every needs --randomize SEED"), std::string::npos) << every_err;
}

}  // namespace
}  // namespace sim4cv::testing
