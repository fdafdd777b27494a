// Found by a hostile-user probe, against the real daemon: lockstep clients that send
// every Step they may and never read made the daemon render and hold 64
// frames each, and the frame pool kept that peak after they left. Now a
// lockstep client that does not read holds the simulation back once
// limits::kLockstepFramesQueued of its frames wait (plus the one its
// transport is sending), and the pool gives back what a burst left.
#include <algorithm>
#include <chrono>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "server/common/limits.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/support/sanitizer_build.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

constexpr int kClients = 3;
constexpr uint32_t kWidth = 1280, kHeight = 720;
// RGB8 + float depth + uint16 instance ids, as the daemon's pooled Frame holds them.
constexpr std::size_t kFrameBytes = std::size_t{kWidth} * kHeight * 30;  // every pixel channel (kAllChannels)
constexpr std::size_t kMiB = std::size_t{1} << 20;
// The most frames one such client can make the daemon hold: its queue and
// the one being sent.
constexpr std::size_t kHeldPerClient = limits::kLockstepFramesQueued + 1;

class FramesHeldTest : public DaemonTest {
 protected:
  void SetUp() override {
    StartDaemon();
    observer_ = Connect("observer");
    for (int i = 0; i < kClients; ++i) {
      const std::string name = "big" + std::to_string(i);
      observer_->AddCamera({.name = name, .width = kWidth, .height = kHeight, .pitch_down_deg = 20,
                            .x = -60.0 + 10 * i, .y = -42, .z = 10});
      silent_.push_back(Connect("silent" + std::to_string(i)));
      silent_.back()->Subscribe(name, kAllChannels, proto::DELIVERY_LOCKSTEP);
    }
    // One round that is read, so the renderer's targets and a frame of each
    // camera exist before the baseline is taken.
    for (auto& client : silent_) client->Step();
    for (auto& client : silent_) {
      proto::Frame frame;
      ASSERT_TRUE(client->ReceiveFrame(frame, 30000ms));
      ASSERT_EQ(frame.width(), kWidth);
    }
  }

  uint64_t FrameId() { return observer_->GetState().frame_id(); }

  // Polls until the simulation has not advanced for `quiet` (or `limit`
  // passed); returns the highest RSS seen meanwhile.
  std::size_t WaitUntilStill(std::chrono::milliseconds quiet, std::chrono::seconds limit) {
    std::size_t peak = daemon_->rss_bytes();
    uint64_t last = FrameId();
    auto last_change = Clock::now();
    const auto deadline = Clock::now() + limit;
    while (Clock::now() - last_change < quiet && Clock::now() < deadline) {
      std::this_thread::sleep_for(100ms);
      peak = std::max(peak, daemon_->rss_bytes());
      const uint64_t now = FrameId();
      if (now != last) {
        last = now;
        last_change = Clock::now();
      }
    }
    return peak;
  }

  std::unique_ptr<Client> observer_;  // never subscribes: asks GetState
  std::vector<std::unique_ptr<Client>> silent_;
};

TEST_F(FramesHeldTest, LockstepClientsThatNeverReadHoldAFewFramesAndTheMemoryComesBack) {
  std::this_thread::sleep_for(2500ms);  // the pool's trim after the warm-up round
  const std::size_t baseline = daemon_->rss_bytes();
  const uint64_t start = FrameId();

  // Every Step the protocol allows, and no reading.
  for (auto& client : silent_) {
    for (std::size_t i = 0; i < limits::kMaxOutstandingSteps; ++i) client->Step();
  }
  const std::size_t peak = WaitUntilStill(1500ms, 90s);
  const uint64_t advanced = FrameId() - start;
  // Each advance renders one frame per client; a client's frames stop at
  // kHeldPerClient (one more would need the socket to take a whole frame).
  EXPECT_LE(advanced, kHeldPerClient + 1) << "the daemon went on rendering for clients that do not read";
  EXPECT_GE(advanced, 1u);
  // The bound this computes to: every client's frames, the pool's spare and
  // 64 MiB for everything else (buffers, the allocator).
  const std::size_t bound = baseline + (kClients * kHeldPerClient + limits::kFramePoolSpare) * kFrameBytes + 64 * kMiB;
  if (kRssBoundsHold) {
    EXPECT_LE(peak, bound) << "RSS peaked at " << peak / kMiB << " MiB; baseline " << baseline / kMiB
                           << " MiB, bound " << bound / kMiB << " MiB";
  }
  std::cout << "[ numbers  ] baseline " << baseline / kMiB << " MiB, peak " << peak / kMiB << " MiB (bound "
            << bound / kMiB << " MiB), " << advanced << " frames advanced for 64 Steps\n";

  // The rule is "lockstep waits for them to read": reading, they get every
  // frame in order, and the simulation goes on.
  std::vector<uint64_t> next(kClients, 0);
  for (int round = 0; round < 6; ++round) {
    for (int i = 0; i < kClients; ++i) {
      proto::Frame frame;
      ASSERT_TRUE(silent_[static_cast<std::size_t>(i)]->ReceiveFrame(frame, 30000ms)) << "client " << i;
      if (round > 0) {
        EXPECT_EQ(frame.frame_id(), next[static_cast<std::size_t>(i)]) << "client " << i;
      }
      next[static_cast<std::size_t>(i)] = frame.frame_id() + 1;
      EXPECT_EQ(frame.dropped_frames(), 0u);
    }
  }
  EXPECT_GE(FrameId() - start, 6u);

  // They leave: the memory they made the daemon take goes back (the pool
  // keeps kFramePoolSpare frames, as it did at the baseline; 12 MiB for the
  // allocator, which once kept 8.7 MiB beside busy loops: still less than
  // two held 1080p RGB frames).
  silent_.clear();
  const std::size_t near_baseline = baseline + 12 * kMiB;
  std::size_t after = daemon_->rss_bytes();
  for (const auto deadline = Clock::now() + 20s; after > near_baseline && Clock::now() < deadline;) {
    std::this_thread::sleep_for(200ms);
    after = daemon_->rss_bytes();
  }
  if (kRssBoundsHold) {
    EXPECT_LE(after, near_baseline) << "RSS stayed at " << after / kMiB << " MiB after the clients left; baseline "
        << baseline / kMiB << " MiB";
  }
  std::cout << "[ numbers  ] after they left: " << after / kMiB << " MiB\n";

  // And the daemon serves a new lockstep client as before.
  observer_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  for (int i = 0; i < 3; ++i) EXPECT_GT(observer_->StepAndReceive().frame_id(), 0u);
}

// A client that keeps kMaxOutstandingSteps Steps in flight and reads as it
// goes gets every frame, in order: the bound holds the simulation back only
// while it is behind, and each frame it reads lets the next be made.
TEST_F(FramesHeldTest, PipeliningClientsGetEveryFrameInOrder) {
  std::vector<uint64_t> next(kClients, 0);
  for (auto& client : silent_) {
    for (int i = 0; i < 12; ++i) client->Step();
  }
  for (int round = 0; round < 12; ++round) {
    for (int i = 0; i < kClients; ++i) {
      proto::Frame frame;
      ASSERT_TRUE(silent_[static_cast<std::size_t>(i)]->ReceiveFrame(frame, 30000ms))
          << "client " << i << ", round " << round;
      if (round > 0) {
        EXPECT_EQ(frame.frame_id(), next[static_cast<std::size_t>(i)]);
      }
      next[static_cast<std::size_t>(i)] = frame.frame_id() + 1;
    }
  }
  EXPECT_EQ(next[0], next[1]);
  EXPECT_EQ(next[1], next[2]);
}

}  // namespace
}  // namespace sim4cv::testing
