// Replay (--replay): the car and the UAV follow a recorded run log frame by
// frame, so the cameras render exactly what the recorded run rendered; past
// the log's end they hold the last pose; files that are no usable log are
// refused at start, naming them.
#include <algorithm>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/sim/log/run_log_writer.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/integration/run_log_fixture.h"

namespace sim4cv::testing {
namespace {

// Every frame of `camera` over `frames` lockstep steps, with its state.
std::vector<proto::Frame> RunUavCamera(DaemonProcess& daemon, int frames, bool press_the_throttle,
                                       const std::string& camera = "uav") {
  Client client;
  client.Connect("127.0.0.1", daemon.tcp_port(), "replay");
  client.Subscribe(camera, kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  std::vector<proto::Frame> received;
  for (int i = 0; i < frames; ++i) {
    // Manual controls move a simulated car; a replayed one ignores them.
    if (press_the_throttle && i == 10) client.SendControls(1, 0.5f, 1.0f, 0.0f);
    received.push_back(client.StepAndReceive());
  }
  client.Close();
  EXPECT_EQ(daemon.Stop(), 0) << daemon.stderr_text();
  return received;
}

TEST(ReplayTest, ReplayRendersTheRecordedRunFrameForFrame) {
  ScratchDir dir;
  const std::string path = dir / "recorded.s4log";
  DaemonProcess recorder({"--log", path});
  const std::vector<proto::Frame> recorded = RunUavCamera(recorder, 90, false);
  const LogContents log = ReadLog(path);
  ASSERT_EQ(log.records.size(), 90u);

  DaemonProcess player({"--replay", path});
  const std::vector<proto::Frame> replayed = RunUavCamera(player, 95, true);
  for (std::size_t i = 0; i < 90; ++i) {
    const proto::Frame& was = recorded[i];
    const proto::Frame& is = replayed[i];
    ASSERT_EQ(is.frame_id(), log.records[i].frame_id);
    ExpectSamePoses(is.state(), log.records[i]);
    // Same poses, same renderer: the same pixels, depths, mask and boxes.
    ASSERT_EQ(is.images_size(), was.images_size());
    for (int c = 0; c < is.images_size(); ++c) {
      EXPECT_TRUE(is.images(c).data() == was.images(c).data()) << "frame " << i + 1 << ", image " << c << " differs";
    }
    EXPECT_EQ(is.boxes_size(), was.boxes_size());
    for (int b = 0; b < std::min(is.boxes_size(), was.boxes_size()); ++b) {
      EXPECT_EQ(is.boxes(b).SerializeAsString(), was.boxes(b).SerializeAsString()) << "frame " << i + 1;
    }
  }
  // Past the end of the log: the last pose, at rest.
  const Pose13 last_car = PoseOf(log.records.back().entities[0].body);
  for (std::size_t i = 90; i < replayed.size(); ++i) {
    const proto::EntityState& car = replayed[i].state().entities(0);
    EXPECT_EQ(replayed[i].frame_id(), i + 1);
    for (std::size_t k = 0; k < 7; ++k) EXPECT_EQ(PoseOf(car)[k], last_car[k]) << "frame " << i + 1;
    for (std::size_t k = 7; k < 13; ++k) EXPECT_EQ(PoseOf(car)[k], 0.0) << "frame " << i + 1;
  }
}

// Traffic is logged (every moving car and walker, as entities after the
// map's objects) and a replay puts it back where it was: the first-person
// camera, which sees it up close, renders the recorded run byte for byte.
TEST(ReplayTest, ReplayWithTrafficRendersTheRecordedRun) {
  ScratchDir dir;
  const std::string path = dir / "traffic.s4log";
  const std::vector<std::string> city = {"--map", SourcePath("scenes/driving/train/01_urban.map"), "--traffic-cars",
                                         "20", "--traffic-pedestrians", "30", "--traffic-parked", "20"};
  std::vector<std::string> record_args = city, replay_args = city;
  record_args.insert(record_args.end(), {"--log", path});
  replay_args.insert(replay_args.end(), {"--replay", path});
  DaemonProcess recorder(record_args);
  const std::vector<proto::Frame> recorded = RunUavCamera(recorder, 60, false, "car_front");
  const LogContents log = ReadLog(path);
  ASSERT_EQ(log.records.size(), 60u);
  EXPECT_EQ(log.records[0].entities.size(), 2u + 20u + 30u) << "the car, the UAV, the traffic cars and the walkers";
  DaemonProcess player(replay_args);
  const std::vector<proto::Frame> replayed = RunUavCamera(player, 60, false, "car_front");
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    for (int c = 0; c < recorded[i].images_size(); ++c) {
      ASSERT_TRUE(replayed[i].images(c).data() == recorded[i].images(c).data())
          << "frame " << i + 1 << ", image " << c << " differs";
    }
  }
}

// Starting with `args` fails, and the message names `file`.
void ExpectRefusal(const std::vector<std::string>& args, const std::string& file, const std::string& reason) {
  try {
    DaemonProcess daemon(args);
    ADD_FAILURE() << "the daemon started with " << file;
  } catch (const std::runtime_error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(file), std::string::npos) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
}

TEST(ReplayTest, FilesThatAreNoUsableLogAreRefusedNamingThem) {
  ScratchDir dir;
  ExpectRefusal({"--replay", dir / "missing.s4log"}, dir / "missing.s4log", "No such file");

  const std::string text = dir / "notes.txt";
  std::ofstream(text) << "not a run log, but long enough to hold a header\n";
  ExpectRefusal({"--replay", text}, text, "not a sim4cv run log");

  // A real log, of another scene.
  const std::string other = dir / "other.s4log";
  runlog::RunLogHeader header;
  header.scene_name = "tracking_easy_urban";
  header.frame_hz = 30;
  runlog::RunLogWriter(other, header).Close();
  ExpectRefusal({"--replay", other}, other, "recorded on scene 'tracking_easy_urban', not 'default'");
}

}  // namespace
}  // namespace sim4cv::testing
