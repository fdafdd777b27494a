// The daemon on shipped tile maps: the target car drives the map's route,
// the UAV camera keeps it in view, and desert and urban forms look different.
#include <cmath>
#include <string>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

std::string MapPath(const std::string& relative) { return SourcePath("scenes/" + relative); }

// Mean of the RGB channel over the whole image.
double MeanRgb(const proto::Frame& frame, int component) {
  const auto rgb = FindImage(frame, proto::CHANNEL_RGB);
  double sum = 0;
  const std::size_t pixels = static_cast<std::size_t>(frame.width()) * frame.height();
  for (std::size_t i = 0; i < pixels; ++i) sum += rgb->data[i * 3 + static_cast<std::size_t>(component)];
  return sum / static_cast<double>(pixels);
}

TEST_F(DaemonTest, TrackingMapKeepsTheTargetInTheUavCamera) {
  StartDaemon({"--map", MapPath("tracking/hard_urban.map"), "--car-speed", "8"});
  auto client = Connect();
  EXPECT_EQ(client->welcome().scene_name(), "tracking_hard_urban");
  client->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  int frames_with_car = 0;
  bool saw_tree = false;
  for (int i = 0; i < 300; ++i) {  // 10 s through the hard map's tight bends at 8 m/s
    const proto::Frame& frame = client->StepAndReceive();
    for (const auto& box : frame.boxes()) {
      frames_with_car += box.object_id() == 1;
      saw_tree = saw_tree || box.object_class() == proto::OBJECT_CLASS_TREE;
    }
  }
  EXPECT_EQ(frames_with_car, 300) << "the UAV camera lost the car";
  EXPECT_TRUE(saw_tree) << "the hard map's trees stand by the road";
  const proto::State state = client->GetState();
  const double speed = std::hypot(state.entities(0).linear_velocity().x(), state.entities(0).linear_velocity().y());
  EXPECT_NEAR(speed, 8.0, 1.0);
}

TEST_F(DaemonTest, DesertAndUrbanFormsRenderDifferently) {
  double green[2] = {0, 0};
  const char* forms[2] = {"tracking/easy_desert.map", "tracking/easy_urban.map"};
  for (int form = 0; form < 2; ++form) {
    StartDaemon({"--map", MapPath(forms[form])});
    auto client = Connect();
    client->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
    for (int i = 0; i < 30; ++i) client->StepAndReceive();
    const proto::Frame& frame = client->StepAndReceive();
    green[form] = MeanRgb(frame, 1) - 0.5 * (MeanRgb(frame, 0) + MeanRgb(frame, 2));
    client->Close();
    EXPECT_EQ(daemon_->Stop(), 0);
    daemon_.reset();
  }
  // Sand is red-yellow (green below the red/blue mean + a margin), lawn is green.
  EXPECT_GT(green[1] - green[0], 15.0) << "desert " << green[0] << ", urban " << green[1];
}

TEST(MapSceneTest, MissingMapFileIsRefusedNamingIt) {
  try {
    DaemonProcess daemon({"--map", "/no/such.map"});
    FAIL() << "the daemon started on a missing map";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/no/such.map"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace sim4cv::testing
