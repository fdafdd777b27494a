// Realtime mode and newest-frame delivery: slow clients drop frames (counted),
// a client that stops reading never slows the simulation or other clients.
#include <chrono>
#include <thread>

#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

TEST_F(DaemonTest, RealtimeRefusesLockstepDelivery) {
  StartDaemon({"--mode", "realtime"});
  auto client = Connect();
  EXPECT_EQ(client->welcome().mode(), proto::SIM_MODE_REALTIME);
  try {
    client->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
    FAIL() << "lockstep delivery accepted in realtime mode";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_INVALID_STATE);
    EXPECT_NE(std::string(error.what()).find("DELIVERY_NEWEST"), std::string::npos) << error.what();
  }
}

TEST_F(DaemonTest, SlowNewestFrameClientDropsAndCountsFrames) {
  StartDaemon({"--mode", "realtime", "--frame-hz", "60", "--physics-hz", "240"});
  auto client = Connect();
  client->Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, proto::DELIVERY_NEWEST);
  proto::Frame frame;
  ASSERT_TRUE(client->ReceiveFrame(frame, 5000ms));
  const uint64_t first_id = frame.frame_id();
  // Frames dropped before the first one arrived (a busy machine) are older than it.
  const uint64_t dropped_before = frame.dropped_frames();
  uint64_t received = 1;
  // Read one frame every 100 ms while the daemon renders one every ~17 ms,
  // until it has produced 40 since the first (on a loaded machine it may
  // render slower than 60 Hz: then it takes more reads).
  for (int i = 0; i < 60 && frame.frame_id() - first_id < 40; ++i) {
    std::this_thread::sleep_for(100ms);
    ASSERT_TRUE(client->ReceiveFrame(frame, 5000ms));
    ++received;
  }
  ASSERT_GE(frame.frame_id() - first_id, 40u) << "the daemon rendered under 7 frames/s";
  const uint64_t produced = frame.frame_id() - first_id + 1;
  const uint64_t dropped = frame.dropped_frames() - dropped_before;
  EXPECT_GT(dropped, 0u) << "a 10 Hz reader of a 60 Hz stream must drop frames";
  // Every frame produced since the first one was either delivered, dropped,
  // or is still in the socket buffers (at most a handful of frames of this size).
  EXPECT_LE(received + dropped, produced);
  EXPECT_GE(received + dropped + 8, produced);
  // Newest-frame delivery: after a pause the client gets a recent frame, not a backlog.
  std::this_thread::sleep_for(300ms);
  ASSERT_TRUE(client->ReceiveFrame(frame, 5000ms));
  const uint64_t after_pause = frame.frame_id();
  proto::Frame next;
  ASSERT_TRUE(client->ReceiveFrame(next, 5000ms));
  EXPECT_GT(next.frame_id(), after_pause);
}

TEST_F(DaemonTest, ClientThatStopsReadingDoesNotSlowOthers) {
  StartDaemon({"--mode", "realtime", "--frame-hz", "30"});
  auto stuck = Connect("stuck");
  stuck->Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK}, proto::DELIVERY_NEWEST);
  auto reader = Connect("reader");
  reader->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_NEWEST);
  proto::Frame frame;
  ASSERT_TRUE(reader->ReceiveFrame(frame, 5000ms));
  const uint64_t first = frame.frame_id();
  const auto start = std::chrono::steady_clock::now();
  int frames = 0;
  while (std::chrono::steady_clock::now() - start < 2s) {
    ASSERT_TRUE(reader->ReceiveFrame(frame, 2000ms));
    ++frames;
  }
  // 2 s at 30 Hz is 60 frames; the stuck client's full socket must not matter.
  EXPECT_GE(frame.frame_id() - first, 50u);
  EXPECT_GE(frames, 45);
  EXPECT_EQ(frame.dropped_frames(), 0u) << "a reader that keeps up should not drop";
}

}  // namespace
}  // namespace sim4cv::testing
