// Unit tests of the queue from the network threads into the sim thread
// (server/session/command_queue.h): its bound and the memory a burst leaves.
#include "server/session/command_queue.h"

#include <gtest/gtest.h>

#include <vector>

#include "server/common/limits.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::session {
namespace {

Command Controls() { return {1, ControlsCommand{1, 0, 0.5f, 0, nullptr}}; }

TEST(CommandQueueTest, TryPostRefusesPastTheBoundButPostAlwaysQueues) {
  CommandQueue queue;
  for (std::size_t i = 0; i < limits::kMaxQueuedCommands; ++i) ASSERT_TRUE(queue.TryPost(Controls())) << i;
  EXPECT_FALSE(queue.TryPost(Controls()));
  queue.Post({1, StepCommand{}});  // bounded per client elsewhere: never refused here
  queue.Post({1, DisconnectCommand{}});
  std::vector<Command> drained;
  queue.Drain(drained);
  ASSERT_EQ(drained.size(), limits::kMaxQueuedCommands + 2);
  EXPECT_TRUE(std::holds_alternative<DisconnectCommand>(drained.back().body));
  EXPECT_TRUE(queue.TryPost(Controls()));
}

TEST(CommandQueueTest, ABurstsCapacityIsGivenBackWithinTwoDrains) {
  CommandQueue queue;
  std::vector<Command> drained;
  for (std::size_t i = 0; i < limits::kMaxQueuedCommands; ++i) queue.TryPost(Controls());
  queue.Drain(drained);
  EXPECT_GE(drained.capacity(), limits::kMaxQueuedCommands);
  queue.Drain(drained);  // the burst's buffer comes back empty and is replaced
  queue.Drain(drained);  // and the other one too
  EXPECT_LE(drained.capacity(), CommandQueue::kKeptCommands);
  queue.Drain(drained);
  EXPECT_LE(drained.capacity(), CommandQueue::kKeptCommands);
}

}  // namespace
}  // namespace sim4cv::session
