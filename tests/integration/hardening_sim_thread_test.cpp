// The hardening findings (docs/reliability.md) against the real daemon, the sim thread's side: a LoadMap that
// once terminated the daemon is an Error and the daemon serves on (finding
// 1), departed clients' tracker outputs leave State and the run log (finding
// 6), and a FIFO named by --map, --scene, --replay or --log is refused at
// start instead of hanging it.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <thread>

#include "tests/integration/run_log_fixture.h"
#include "tests/integration/run_to_exit.h"
#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A small valid map with `tile_size` as written.
std::string MapWithTileSize(const std::string& tile_size) {
  return "sim4cv-map 1\nname huge\ntile_size " + tile_size +
         "\ngrid 2 2\n##\n##\nend\nroute loop closed\ntiles 0,0 1,0 1,1 0,1\n";
}

class SimThreadHardeningTest : public ConfigureTest {};

// docs/reliability.md, finding 1: `tile_size 3e9` made the ground mesh throw std::bad_alloc and
// `1e300` a non-finite car pose; either left the sim thread and terminated
// the daemon. Now each is that client's Error (with its request_id), and the
// world and its frames go on as before.
TEST_F(SimThreadHardeningTest, LoadMapWithAHugeTileSizeIsAnErrorAndFramesGoOn) {
  StartDaemon();
  auto client = Connect("huge-tiles");
  client->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  EXPECT_EQ(StepFrames(*client, 3).frame_id(), 3u);
  const std::string scene = Connect("watcher")->welcome().scene_name();
  for (const char* tile_size : {"3e9", "1e300"}) {
    ExpectRefused([&] { client->LoadMapText(MapWithTileSize(tile_size)); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                  {"LoadMap.text", "tile_size", "limits::kMaxMapTileSize"});
  }
  const proto::Frame& frame = StepFrames(*client, 3);
  EXPECT_EQ(frame.frame_id(), 6u) << "the same world steps on";
  EXPECT_EQ(frame.images_size(), 1) << "rendered as before";
  EXPECT_EQ(Connect("after")->welcome().scene_name(), scene);
}

// docs/reliability.md, finding 6: every client that ever sent a TrackerOutput kept an entry in
// State::tracker_reports, copied into each frame's State and each run-log
// record. Clients report and leave; the records after they left hold only
// the client still connected.
TEST_F(SimThreadHardeningTest, TrackerOutputsOfDepartedClientsAreForgotten) {
  ScratchDir dir;
  const std::string log = dir / "run.s4log";
  StartDaemon({"--log", log});
  auto stepper = Connect("stepper");
  stepper->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  stepper->StepAndReceive();
  stepper->SendTrackerOutput(1, 1, 2, 3, 4, 0.5f);
  for (int round = 0; round < 3; ++round) {
    std::vector<std::unique_ptr<Client>> trackers;
    for (int i = 0; i < 4; ++i) {
      trackers.push_back(Connect("tracker" + std::to_string(i)));
      // A box belongs to the camera its tracker subscribes to (newest: it holds no one back).
      trackers.back()->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_NEWEST);
      trackers.back()->SendTrackerOutput(1, 10.0f + i, 20, 30, 40, 0.9f);
      trackers.back()->GetState();  // the report was read before this answer
    }
    stepper->StepAndReceive();
    for (auto& tracker : trackers) tracker->Close();
  }
  // The disconnects reach the sim thread within a few of its steps.
  for (int i = 0; i < 20; ++i) {
    std::this_thread::sleep_for(20ms);
    stepper->StepAndReceive();
  }
  stepper->Close();
  ASSERT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
  const std::string stderr_text = daemon_->stderr_text();
  daemon_.reset();
  const LogContents contents = ReadLog(log);
  ASSERT_FALSE(contents.records.empty());
  bool saw_trackers = false;
  for (const auto& record : contents.records) saw_trackers |= record.tracker_boxes.size() > 1;
  EXPECT_TRUE(saw_trackers) << "while connected, their reports were logged";
  const std::size_t last_boxes = contents.records.back().tracker_boxes.size();
  EXPECT_EQ(last_boxes, 1u) << "only the stepper's report is left, frame " << contents.records.back().frame_id << "\n"
                            << stderr_text;
}

// docs/reliability.md, finding 7: open() on a FIFO without a writer (or reader) blocked the
// daemon's start with SIGTERM already blocked; now each flag refuses it.
TEST(FifoArgumentTest, EveryFileFlagRefusesAFifoWithExitStatus2) {
  ScratchDir dir;
  const std::string fifo = dir / "pipe";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string map = SourcePath("scenes/tracking/easy_desert.map");
  for (const auto& args : std::vector<std::vector<std::string>>{{"--map", fifo},
                                                               {"--scene", fifo},
                                                               {"--replay", fifo},
                                                               {"--map", map, "--log", fifo}}) {
    const auto start = Clock::now();
    const auto [status, text] = RunToExit(args);
    EXPECT_EQ(status, 2) << args[args.size() - 2] << ": " << text;
    EXPECT_LT(Clock::now() - start, 15s) << args[args.size() - 2];
    for (const std::string& part : {fifo, std::string("is a FIFO (named pipe), not a regular file")}) {
      EXPECT_NE(text.find(part), std::string::npos) << args[args.size() - 2] << ": '" << part << "' not in: " << text;
    }
  }
}

}  // namespace
}  // namespace sim4cv::testing
