// Camera effects against the real daemon: flags and Configure.set_effects
// turn them on; under every effect each frame's boxes are the tight boxes of
// its mask; effects on RGB leave depth, mask, semantic labels and boxes
// byte-identical; a lens reaches the frame's intrinsics; runs with every
// effect on repeat byte for byte; bad values are refused naming the range.
#include <algorithm>
#include <cstring>

#include "server/wire/effects_wire.h"
#include "tests/integration/run_to_exit.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

class EffectsTest : public ConfigureTest {};

std::string Plane(const proto::Frame& frame, proto::Channel channel) {
  const auto image = FindImage(frame, channel);
  return std::string(reinterpret_cast<const char*>(image->data), std::size_t{image->stride} * image->height);
}

// Every box must be the tight box of its object's pixels in the mask.
void ExpectBoxesAreTheMasksTightBoxes(const proto::Frame& frame) {
  const auto mask = FindImage(frame, proto::CHANNEL_MASK);
  ASSERT_TRUE(mask.has_value());
  ASSERT_GT(frame.boxes_size(), 0) << "something labelled in view";
  for (const proto::Box& box : frame.boxes()) {
    uint32_t x0 = mask->width, y0 = mask->height, x1 = 0, y1 = 0, count = 0;
    for (uint32_t row = 0; row < mask->height; ++row) {
      const auto* line = reinterpret_cast<const uint16_t*>(mask->data + std::size_t{row} * mask->stride);
      for (uint32_t column = 0; column < mask->width; ++column) {
        if (line[column] != box.object_id()) continue;
        x0 = std::min(x0, column);
        y0 = std::min(y0, row);
        x1 = std::max(x1, column + 1);
        y1 = std::max(y1, row + 1);
        ++count;
      }
    }
    EXPECT_EQ(box.x(), x0) << "object " << box.object_id();
    EXPECT_EQ(box.y(), y0) << "object " << box.object_id();
    EXPECT_EQ(box.width(), x1 - x0) << "object " << box.object_id();
    EXPECT_EQ(box.height(), y1 - y0) << "object " << box.object_id();
    EXPECT_EQ(box.visible_pixels(), count) << "object " << box.object_id();
    EXPECT_GT(box.visibility(), 0.0f);
    EXPECT_LE(box.visibility(), 1.0f);
  }
}

proto::CameraEffects Each(const std::string& name) {
  proto::CameraEffects effects;
  if (name == "antialias") effects.set_antialias(1);
  if (name == "exposure") effects.set_exposure_ev(-1.5);
  if (name == "white balance") effects.set_white_balance_k(3000);
  if (name == "motion blur") effects.set_motion_blur(1);
  if (name == "jpeg") effects.set_jpeg_quality(20);
  if (name == "lens") {
    effects.set_k1(-0.25);
    effects.set_k2(0.06);
    effects.set_p1(0.001);
  }
  return effects;
}

TEST_F(EffectsTest, FlagsTurnEffectsOnAndTheFrameCarriesTheLens) {
  StartDaemon({"--lens-k1", "-0.2", "--lens-p2", "0.001", "--jpeg", "80", "--antialias", "1"});
  const auto client = Connect("effects");
  const proto::WorldInfo world = client->GetWorld();
  EXPECT_EQ(world.effects().k1(), -0.2);
  EXPECT_EQ(world.effects().p2(), 0.001);
  EXPECT_EQ(world.effects().jpeg_quality(), 80);
  EXPECT_EQ(world.effects().antialias(), 1);
  EXPECT_EQ(world.effects().white_balance_k(), 6500) << "every field is reported";
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  const proto::Frame& frame = StepFrames(*client, 5);
  EXPECT_EQ(frame.camera_intrinsics().k1(), -0.2);
  EXPECT_EQ(frame.camera_intrinsics().p2(), 0.001);
  EXPECT_EQ(frame.camera_intrinsics().k2(), 0.0);
  ExpectBoxesAreTheMasksTightBoxes(frame);
}

TEST_F(EffectsTest, EveryEffectKeepsBoxesTheTightBoxesOfTheMaskAndRgbEffectsChangeOnlyRgb) {
  StartDaemon();
  const auto client = Connect("effects");
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  const proto::Frame plain = StepFrames(*client, 45);  // the car is up to speed: things move
  for (const std::string name : {"antialias", "exposure", "white balance", "motion blur", "jpeg", "lens"}) {
    SCOPED_TRACE(name);
    client->Reset();
    proto::CameraEffects off;  // every field back to its default
    wire::FillEffects(effects::CameraEffects{}, off);
    client->SetEffects(off);
    const proto::WorldInfo world = client->SetEffects(Each(name));
    const proto::Frame frame = StepFrames(*client, 45);
    ASSERT_EQ(frame.frame_id(), plain.frame_id());
    ExpectBoxesAreTheMasksTightBoxes(frame);
    EXPECT_TRUE(Plane(frame, proto::CHANNEL_RGB) != Plane(plain, proto::CHANNEL_RGB)) << "the effect shows";
    if (name == "lens") {
      EXPECT_EQ(world.effects().k1(), -0.25);
      EXPECT_EQ(frame.camera_intrinsics().k1(), -0.25);
      EXPECT_TRUE(Plane(frame, proto::CHANNEL_MASK) != Plane(plain, proto::CHANNEL_MASK)) << "the lens bends the mask";
      continue;
    }
    EXPECT_EQ(frame.camera_intrinsics().k1(), 0.0);
    EXPECT_TRUE(Plane(frame, proto::CHANNEL_DEPTH) == Plane(plain, proto::CHANNEL_DEPTH)) << "DEPTH";
    EXPECT_TRUE(Plane(frame, proto::CHANNEL_MASK) == Plane(plain, proto::CHANNEL_MASK)) << "MASK";
    EXPECT_TRUE(Plane(frame, proto::CHANNEL_SEMANTIC) == Plane(plain, proto::CHANNEL_SEMANTIC)) << "SEMANTIC";
    EXPECT_TRUE(Plane(frame, proto::CHANNEL_FLOW) == Plane(plain, proto::CHANNEL_FLOW)) << "FLOW";
    ASSERT_EQ(frame.boxes_size(), plain.boxes_size());
    for (int i = 0; i < plain.boxes_size(); ++i) {
      EXPECT_EQ(frame.boxes(i).SerializeAsString(), plain.boxes(i).SerializeAsString());
    }
  }
}

// Two daemons with every effect on (and sensor noise) give the same frames.
TEST_F(EffectsTest, RunsWithEveryEffectRepeatByteForByte) {
  const std::vector<std::string> args = {"--antialias",   "1",   "--motion-blur", "0.5",  "--white-balance", "4500",
                                         "--exposure-ev", "0.5", "--lens-k1",     "-0.2", "--lens-k2",       "0.04",
                                         "--jpeg",        "60",  "--noise-read",  "2"};
  std::vector<std::string> first;
  for (int run = 0; run < 2; ++run) {
    StartDaemon(args);
    const auto client = Connect("repeat");
    client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
    for (int i = 0; i < 6; ++i) {
      const proto::Frame& frame = client->StepAndReceive();
      std::string all;
      for (const proto::Channel channel : kAllChannels) {
        if (channel != proto::CHANNEL_BOXES) all += Plane(frame, channel);
      }
      for (const proto::Box& box : frame.boxes()) all += box.SerializeAsString();
      if (run == 0) {
        first.push_back(all);
      } else {
        EXPECT_TRUE(all == first[static_cast<std::size_t>(i)]) << "frame " << i + 1 << " differs";
      }
    }
    daemon_.reset();
  }
}

TEST_F(EffectsTest, BadValuesAreRefusedNamingTheRangeAndNothingChanges) {
  StartDaemon();
  const auto client = Connect("effects");
  proto::CameraEffects blur;
  blur.set_motion_blur(2);
  ExpectRefused([&] { client->SetEffects(blur); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SetEffects.motion_blur 2 is outside 0..1 frames"});
  proto::CameraEffects jpeg;
  jpeg.set_jpeg_quality(95.5);
  ExpectRefused([&] { client->SetEffects(jpeg); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"SetEffects.jpeg_quality 95.5 is not a whole number"});
  // Each coefficient in range, together a lens that folds the image.
  proto::CameraEffects half;
  half.set_k1(-0.5);
  client->SetEffects(half);
  proto::CameraEffects more;
  more.set_k2(-0.4);
  ExpectRefused([&] { client->SetEffects(more); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"the lens k1=-0.5 k2=-0.4 k3=0 folds the image", "use smaller coefficients"});
  EXPECT_EQ(client->GetWorld().effects().k2(), 0.0) << "nothing changed";
  EXPECT_EQ(client->GetWorld().effects().k1(), -0.5);
}

TEST(EffectsFlagsTest, BadFlagsStopTheDaemonNamingTheValue) {
  const auto [status, err] = RunToExit({"--motion-blur", "3"});
  EXPECT_NE(status, 0);
  EXPECT_NE(err.find("--motion-blur is 3; it must be in [0, 1]"), std::string::npos) << err;
  const auto [lens_status, lens_err] = RunToExit({"--lens-k1", "-0.9"});
  EXPECT_NE(lens_status, 0);
  EXPECT_NE(lens_err.find("the lens k1=-0.9 k2=0 k3=0 folds the image at radius 0.40"), std::string::npos) << lens_err;
  const auto [jpeg_status, jpeg_err] = RunToExit({"--jpeg", "7.5"});
  EXPECT_NE(jpeg_status, 0);
  EXPECT_NE(jpeg_err.find("--jpeg 7.5 is not a whole number"), std::string::npos) << jpeg_err;
}

}  // namespace
}  // namespace sim4cv::testing
