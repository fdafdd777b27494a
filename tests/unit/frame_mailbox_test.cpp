// Unit tests of FrameMailbox (server/session/frame_mailbox.*).
#include "server/session/frame_mailbox.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "server/session/command_queue.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::session {
namespace {

class FrameMailboxTest : public ::testing::Test {
 protected:
  FrameRef MakeFrame(uint64_t id) {
    Frame* frame = nullptr;
    FrameRef ref = pool_.Acquire(&frame);
    frame->frame_id = id;
    return ref;
  }

  // Declared first so it outlives the mailbox's refs.
  FramePool pool_;
  FrameMailbox mailbox_;
};

TEST_F(FrameMailboxTest, EmptyTakeGivesAnEmptyRef) {
  EXPECT_FALSE(mailbox_.Take());
  EXPECT_EQ(mailbox_.dropped(), 0u);
}

TEST_F(FrameMailboxTest, DefaultsToNewestDelivery) {
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(1)));
  EXPECT_TRUE(mailbox_.Offer(MakeFrame(2)));
  EXPECT_EQ(mailbox_.dropped(), 1u);
  EXPECT_EQ(mailbox_.Take()->frame_id, 2u);
}

TEST_F(FrameMailboxTest, NewestKeepsOneFrameAndCountsDrops) {
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(1)));
  EXPECT_TRUE(mailbox_.Offer(MakeFrame(2)));
  EXPECT_TRUE(mailbox_.Offer(MakeFrame(3)));
  EXPECT_EQ(mailbox_.dropped(), 2u);
  const FrameRef taken = mailbox_.Take();
  ASSERT_TRUE(taken);
  EXPECT_EQ(taken->frame_id, 3u);
  EXPECT_FALSE(mailbox_.Take());
  // Taking empties it, so the next offer drops nothing.
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(4)));
  EXPECT_EQ(mailbox_.dropped(), 2u);
  EXPECT_EQ(mailbox_.Take()->frame_id, 4u);
}

TEST_F(FrameMailboxTest, NewestTakeOrderOverManyRounds) {
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  std::vector<uint64_t> taken;
  for (uint64_t id = 1; id <= 20; ++id) {
    mailbox_.Offer(MakeFrame(id));
    if (id % 4 == 0) taken.push_back(mailbox_.Take()->frame_id);
  }
  EXPECT_EQ(taken, (std::vector<uint64_t>{4, 8, 12, 16, 20}));
  EXPECT_EQ(mailbox_.dropped(), 15u);
  // Only one frame was ever held: the pool needed at most two (one waiting,
  // one being made).
  EXPECT_LE(pool_.size(), 2u);
}

TEST_F(FrameMailboxTest, LockstepQueuesInFifoOrderUpToItsCapacity) {
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  const uint64_t n = FrameMailbox::kLockstepCapacity;
  ASSERT_GE(n, 2u) << "a pipelining client needs its next frame waiting while it reads";
  ASSERT_LT(n, FrameMailbox::kMaxLockstepBacklog) << "frames held must be fewer than the Steps a client may send";
  for (uint64_t id = 1; id <= n; ++id) EXPECT_FALSE(mailbox_.Offer(MakeFrame(id))) << id;
  EXPECT_EQ(mailbox_.dropped(), 0u);
  for (uint64_t id = 1; id <= n; ++id) {
    const FrameRef frame = mailbox_.Take();
    ASSERT_TRUE(frame) << id;
    EXPECT_EQ(frame->frame_id, id);
  }
  EXPECT_FALSE(mailbox_.Take());
}

// The gate the scheduler reads: full exactly while kLockstepCapacity frames
// wait, whatever the ring's position.
TEST_F(FrameMailboxTest, LockstepGateIsFullWhileTheQueueIs) {
  const auto gate = mailbox_.gate();
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  uint64_t next_in = 1, next_out = 1;
  for (int round = 0; round < 10; ++round) {
    for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) {
      EXPECT_FALSE(gate->full()) << "round " << round << ", " << i << " waiting";
      EXPECT_FALSE(mailbox_.Offer(MakeFrame(next_in++)));
    }
    EXPECT_TRUE(gate->full()) << "round " << round;
    // One taken: room again. Then empty it.
    EXPECT_EQ(mailbox_.Take()->frame_id, next_out++);
    EXPECT_FALSE(gate->full());
    while (next_out < next_in) EXPECT_EQ(mailbox_.Take()->frame_id, next_out++);
  }
  EXPECT_EQ(mailbox_.dropped(), 0u);
  // Reset opens it; newest delivery never closes it.
  for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) mailbox_.Offer(MakeFrame(next_in++));
  ASSERT_TRUE(gate->full());
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  EXPECT_FALSE(gate->full());
  for (int i = 0; i < 5; ++i) mailbox_.Offer(MakeFrame(next_in++));
  EXPECT_FALSE(gate->full());
}

// A full mailbox that gives up a frame wakes the sim thread (waiting in the
// queue), so a lockstep simulation this client held back goes on at once
// rather than at the loop's next timeout.
TEST_F(FrameMailboxTest, TakingFromAFullLockstepMailboxWakesTheQueue) {
  CommandQueue queue;
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP, &queue);
  for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) mailbox_.Offer(MakeFrame(i + 1));
  std::thread reader([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    mailbox_.Take();
  });
  const auto start = std::chrono::steady_clock::now();
  queue.WaitUntil(start + std::chrono::seconds(30));
  reader.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(20)) << "the Take did not wake the queue";
  std::vector<Command> drained;
  queue.Drain(drained);
  EXPECT_TRUE(drained.empty()) << "a wake-up, not a command";
}

TEST_F(FrameMailboxTest, LockstepWrapsAroundTheRing) {
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  uint64_t next_in = 1, next_out = 1;
  // Interleave so head and tail go round the ring several times.
  for (int round = 0; round < 40; ++round) {
    for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) EXPECT_FALSE(mailbox_.Offer(MakeFrame(next_in++)));
    for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) EXPECT_EQ(mailbox_.Take()->frame_id, next_out++);
  }
  EXPECT_FALSE(mailbox_.Take());
  EXPECT_EQ(mailbox_.dropped(), 0u);
}

TEST_F(FrameMailboxTest, LockstepOverflowDropsTheOldest) {
  // The scheduler offers nothing to a full lockstep mailbox; if it did, the
  // oldest frame would give way rather than the mailbox grow.
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  const uint64_t n = FrameMailbox::kLockstepCapacity;
  for (uint64_t id = 1; id <= n; ++id) mailbox_.Offer(MakeFrame(id));
  EXPECT_TRUE(mailbox_.Offer(MakeFrame(n + 1)));
  EXPECT_EQ(mailbox_.dropped(), 1u);
  EXPECT_EQ(mailbox_.Take()->frame_id, 2u);
}

TEST_F(FrameMailboxTest, ResetClearsAndZeroesTheDropCount) {
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  mailbox_.Offer(MakeFrame(1));
  mailbox_.Offer(MakeFrame(2));
  ASSERT_EQ(mailbox_.dropped(), 1u);
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  EXPECT_EQ(mailbox_.dropped(), 0u);
  EXPECT_FALSE(mailbox_.Take());
  // The new rule applies: lockstep keeps both.
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(3)));
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(4)));
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  EXPECT_FALSE(mailbox_.Take());
  EXPECT_FALSE(mailbox_.Offer(MakeFrame(5)));
  EXPECT_TRUE(mailbox_.Offer(MakeFrame(6)));
}

TEST_F(FrameMailboxTest, ResetReturnsWaitingFramesToThePool) {
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  mailbox_.Offer(MakeFrame(1));
  mailbox_.Offer(MakeFrame(2));
  ASSERT_EQ(pool_.size(), 2u);
  mailbox_.Reset(proto::DELIVERY_LOCKSTEP);
  // Both are free again: acquiring two makes no new objects.
  Frame* a = nullptr;
  Frame* b = nullptr;
  const FrameRef ra = pool_.Acquire(&a);
  const FrameRef rb = pool_.Acquire(&b);
  EXPECT_EQ(pool_.size(), 2u);
  EXPECT_NE(a, b);
}

TEST_F(FrameMailboxTest, FramesReturnToThePoolWhenTakenAndReleased) {
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  mailbox_.Offer(MakeFrame(1));
  FrameRef taken = mailbox_.Take();
  ASSERT_TRUE(taken);
  const Frame* address = &*taken;
  // Still held by the taker: a new acquire needs a new object.
  {
    Frame* other = nullptr;
    const FrameRef ref = pool_.Acquire(&other);
    EXPECT_NE(other, address);
    EXPECT_EQ(pool_.size(), 2u);
  }
  taken.reset();
  EXPECT_FALSE(taken);
  // Released: the most recently returned object comes back first, and the
  // pool did not grow.
  Frame* again = nullptr;
  const FrameRef ref = pool_.Acquire(&again);
  EXPECT_EQ(again, address);
  EXPECT_EQ(pool_.size(), 2u);
  // Its contents are as the last user left them (buffers keep capacity).
  EXPECT_EQ(again->frame_id, 1u);
}

TEST_F(FrameMailboxTest, DroppedFramesReturnToThePool) {
  mailbox_.Reset(proto::DELIVERY_NEWEST);
  const Frame* first = nullptr;
  {
    FrameRef ref = MakeFrame(1);
    first = &*ref;
    mailbox_.Offer(ref);
  }
  mailbox_.Offer(MakeFrame(2));  // drops frame 1: the mailbox held its only ref
  Frame* again = nullptr;
  const FrameRef ref = pool_.Acquire(&again);
  EXPECT_EQ(again, first);
  EXPECT_EQ(pool_.size(), 2u);
}

}  // namespace
}  // namespace sim4cv::session
