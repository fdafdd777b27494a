// The daemon's run log (--log): one record per frame holding what the clients
// saw, complete up to every frame a client received even after a SIGKILL,
// and a disk error that stops the log but not the simulation.
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "tests/integration/daemon_fixture.h"
#include "tests/integration/run_log_fixture.h"

namespace sim4cv::testing {
namespace {

constexpr uint16_t kUavCamera = 0, kChaseCamera = 2;  // the default scene's "uav" and "car_chase"

// The car's box (object id 1) in a frame; fails the test if it is not there.
const proto::Box& CarBox(const proto::Frame& frame) {
  for (const auto& box : frame.boxes()) {
    if (box.object_id() == 1) return box;
  }
  ADD_FAILURE() << "frame " << frame.frame_id() << " has no car box";
  static const proto::Box none;
  return none;
}

void ExpectSameBox(const proto::Box& seen, const runlog::GroundTruthBoxLog& logged) {
  EXPECT_EQ(logged.object_id, seen.object_id());
  EXPECT_EQ(logged.x, seen.x());
  EXPECT_EQ(logged.y, seen.y());
  EXPECT_EQ(logged.width, seen.width());
  EXPECT_EQ(logged.height, seen.height());
  EXPECT_EQ(logged.visibility, seen.visibility());
}

class RunLogTest : public DaemonTest {
 protected:
  // A clean shutdown closes the log, so it can be read; TearDown then has nothing left to stop.
  void StopDaemonCleanly() {
    EXPECT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
    daemon_.reset();
  }
};

TEST_F(RunLogTest, LogRecordsEveryFrameAsTheClientsSawIt) {
  ScratchDir dir;
  const std::string path = dir / "run.s4log";
  StartDaemon({"--log", path, "--log-label", "test tracker"});
  auto uav = Connect("uav");
  auto chase = Connect("chase");
  uav->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  chase->Subscribe("car_chase", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);

  std::vector<proto::Frame> uav_frames;
  std::vector<proto::Box> chase_car_boxes;
  proto::Frame chase_frame;
  for (int i = 1; i <= 60; ++i) {
    // A tracker box sent before a Step is applied before that frame.
    if (i == 11) uav->SendTrackerOutput(10, 1.5f, 2.25f, 30.125f, 20.75f, 0.875f);
    if (i == 31) chase->SendTrackerOutput(30, 100.5f, 50.0f, 40.0f, 30.0f, 0.5f);
    chase->Step();
    uav_frames.push_back(uav->StepAndReceive());
    ASSERT_TRUE(chase->ReceiveFrame(chase_frame));
    chase_car_boxes.push_back(CarBox(chase_frame));
  }
  const proto::State last_state = uav->GetState();
  const uint32_t uav_client = uav->welcome().client_id(), chase_client = chase->welcome().client_id();
  uav->Close();
  chase->Close();
  StopDaemonCleanly();

  const LogContents log = ReadLog(path);
  EXPECT_EQ(log.header.label, "test tracker");
  EXPECT_EQ(log.header.scene_name, "default");
  EXPECT_EQ(log.header.frame_hz, 30.0);
  ASSERT_EQ(log.header.cameras.size(), 3u);
  EXPECT_EQ(log.header.cameras[kUavCamera].name, "uav");
  EXPECT_EQ(log.header.cameras[kUavCamera].mounted_on, 2u);
  ASSERT_EQ(log.records.size(), 60u);
  EXPECT_EQ(log.ignored_bytes, 0u);
  for (std::size_t i = 0; i < 60; ++i) {
    const runlog::FrameLogRecord& record = log.records[i];
    const proto::Frame& frame = uav_frames[i];
    ASSERT_EQ(record.frame_id, i + 1);
    ASSERT_EQ(frame.frame_id(), record.frame_id);
    EXPECT_EQ(record.sim_time, frame.sim_time());
    ExpectSamePoses(frame.state(), record);

    // The uav camera's frame was rendered and shows the car; so does car_chase.
    std::map<uint16_t, const runlog::GroundTruthBoxLog*> truth;
    for (const auto& box : record.ground_truth) truth[box.camera] = &box;
    ASSERT_EQ(truth.size(), 2u) << "frame " << record.frame_id;
    ASSERT_TRUE(truth.count(kUavCamera) && truth.count(kChaseCamera));
    ExpectSameBox(CarBox(frame), *truth[kUavCamera]);
    ExpectSameBox(chase_car_boxes[i], *truth[kChaseCamera]);

    // Each client's latest box, once it sent one, with the camera it watches.
    const std::size_t expected_boxes = (i + 1 >= 11) + (i + 1 >= 31);
    ASSERT_EQ(record.tracker_boxes.size(), expected_boxes) << "frame " << record.frame_id;
    for (const auto& box : record.tracker_boxes) {
      if (box.box.client_id == uav_client) {
        EXPECT_EQ(box.camera, kUavCamera);
        EXPECT_EQ(box.box.frame_id, 10u);
        EXPECT_EQ(std::make_tuple(box.box.x, box.box.y, box.box.width, box.box.height, box.box.confidence),
                  std::make_tuple(1.5f, 2.25f, 30.125f, 20.75f, 0.875f));
      } else {
        EXPECT_EQ(box.box.client_id, chase_client);
        EXPECT_EQ(box.camera, kChaseCamera);
        EXPECT_EQ(box.box.frame_id, 30u);
      }
    }
    ASSERT_EQ(record.controls.size(), 1u);
    EXPECT_EQ(record.controls[0].entity_id, 1u);
    EXPECT_FALSE(record.controls[0].command.manual) << "the waypoint follower drives";
    EXPECT_GT(record.controls[0].command.throttle + record.controls[0].command.brake, 0.0f);
  }
  ExpectSamePoses(last_state, log.records.back());
}

TEST(RunLogCrashTest, SigkillKeepsEveryFrameAClientReceived) {
  ScratchDir dir;
  const std::string path = dir / "killed.s4log";
  DaemonProcess daemon({"--log", path});
  Client client;
  client.Connect("127.0.0.1", daemon.tcp_port(), "crash");
  client.Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  std::vector<proto::State> received;
  for (int i = 0; i < 100; ++i) received.push_back(client.StepAndReceive().state());
  client.Step();  // so the kill may land while frame 101 is rendered or written
  ASSERT_EQ(kill(daemon.pid(), SIGKILL), 0);
  while (daemon.running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  EXPECT_EQ(daemon.Stop(), 128 + SIGKILL);

  const LogContents log = ReadLog(path);
  ASSERT_GE(log.records.size(), 100u) << "a frame a client received is missing from the log";
  ASSERT_LE(log.records.size(), 101u);
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    ASSERT_EQ(log.records[i].frame_id, i + 1);
    if (i < received.size()) ExpectSamePoses(received[i], log.records[i]);
  }
  EXPECT_LT(log.ignored_bytes, 1000u) << "more than the record being written was lost";
}

TEST(RunLogDiskErrorTest, AFailedWriteStopsTheLogNotTheSimulation) {
  ScratchDir dir;
  const std::string path = dir / "full.s4log";
  auto daemon = std::make_unique<DaemonProcess>(std::vector<std::string>{"--log", path});
  // The file size limit (RLIMIT_FSIZE) fails writes as a full disk does; set once the daemon
  // runs (a lockstep daemon logs nothing before the first Step), since at its start it would
  // also limit the sanitizer runtimes' own files.
  rlimit limit{16 << 10, 16 << 10};  // ~50 records
  ASSERT_EQ(::prlimit(daemon->pid(), RLIMIT_FSIZE, &limit, nullptr), 0);
  Client client;
  client.Connect("127.0.0.1", daemon->tcp_port(), "full disk");
  client.Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (int i = 1; i <= 200; ++i) ASSERT_EQ(client.StepAndReceive().frame_id(), static_cast<uint64_t>(i));
  client.Close();
  ASSERT_EQ(daemon->Stop(), 0);

  const std::string stderr_text = daemon->stderr_text();
  std::size_t error_lines = 0;
  for (std::size_t at = 0; (at = stderr_text.find("run logging stopped", at)) != std::string::npos; ++at) ++error_lines;
  EXPECT_EQ(error_lines, 1u) << stderr_text;
  EXPECT_NE(stderr_text.find(path + ": write record: File too large"), std::string::npos) << stderr_text;
  EXPECT_NE(stderr_text.find("counter log.write_errors = 1"), std::string::npos) << stderr_text;

  // The writer cut the failed record (~300 bytes) off: the log stops short
  // of the limit and what is there reads back whole.
  const auto size = std::filesystem::file_size(path);
  EXPECT_LE(size, 16u << 10);
  EXPECT_GT(size + 400, 16u << 10);
  const LogContents log = ReadLog(path);
  EXPECT_GT(log.records.size(), 30u);
  for (std::size_t i = 0; i < log.records.size(); ++i) ASSERT_EQ(log.records[i].frame_id, i + 1);
  EXPECT_EQ(log.ignored_bytes, 0u);
}

TEST(RunLogStartTest, AnUnwritableLogIsRefusedNamingIt) {
  try {
    DaemonProcess daemon({"--log", "/no/such/folder/run.s4log"});
    FAIL() << "the daemon started without its log";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("/no/such/folder/run.s4log"), std::string::npos) << error.what();
  }
}

TEST_F(RunLogTest, LogOfAMapRunIsDrawnOnThatMap) {
  ScratchDir dir;
  const std::string map = SourcePath("scenes/tracking/easy_urban.map");
  const std::string log_path = dir / "urban.s4log", png = dir / "urban.png";
  StartDaemon({"--map", map, "--log", log_path});
  auto client = Connect();
  client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 90; ++i) client->StepAndReceive();
  client->Close();
  StopDaemonCleanly();

  const LogContents log = ReadLog(log_path);
  EXPECT_EQ(log.header.scene_name, "tracking_easy_urban");
  EXPECT_EQ(log.header.label, "tracking_easy_urban") << "the label defaults to the scene name";
  EXPECT_EQ(log.header.map_path, map);
  EXPECT_EQ(log.records.size(), 90u);
  // The tool sits in the build tree beside the daemon: server/daemon/sim4cvd, tools/sim4cv_logdraw.
  const auto logdraw = std::filesystem::path(SIM4CVD_PATH).parent_path().parent_path().parent_path() / "tools" /
                       "sim4cv_logdraw";
  const std::string command = logdraw.string() + " --map '" + map + "' --out '" + png + "' '" + log_path + "'";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
  ASSERT_TRUE(std::filesystem::exists(png));
  EXPECT_GT(std::filesystem::file_size(png), 1000u);
}

}  // namespace
}  // namespace sim4cv::testing
