// Unit tests of the lockstep scheduler (server/session/scheduler.*).
#include "server/session/scheduler.h"

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "server/session/frame_mailbox.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::session {
namespace {

constexpr channels::ChannelSet kRgb = channels::Bit(proto::CHANNEL_RGB);

// Records the frames offered to it, tagged with its own name.
class RecordingLink : public ClientLink {
 public:
  RecordingLink(int tag, std::vector<std::pair<int, uint64_t>>* log) : tag_(tag), log_(log) {}
  void OfferFrame(const FrameRef& frame) override {
    frames.push_back(frame->frame_id);
    if (log_) log_->emplace_back(tag_, frame->frame_id);
  }
  void OfferReply(proto::Envelope reply) override { replies.push_back(std::move(reply)); }
  std::vector<uint64_t> frames;
  std::vector<proto::Envelope> replies;

 private:
  int tag_;
  std::vector<std::pair<int, uint64_t>>* log_;
};

class SchedulerTest : public ::testing::Test {
 protected:
  std::shared_ptr<RecordingLink> Link(int tag) { return std::make_shared<RecordingLink>(tag, &delivery_log_); }

  FrameRef MakeFrame(uint64_t id, uint32_t camera) {
    Frame* frame = nullptr;
    FrameRef ref = pool_.Acquire(&frame);
    frame->frame_id = id;
    frame->camera_index = camera;
    return ref;
  }

  FramePool pool_;
  std::vector<std::pair<int, uint64_t>> delivery_log_;
  Scheduler scheduler_;
};

TEST_F(SchedulerTest, NoSubscribersIsNotReady) {
  EXPECT_FALSE(scheduler_.LockstepReady());
  EXPECT_EQ(scheduler_.subscriber_count(), 0u);
  scheduler_.AddStep(7);  // unknown client: ignored
  EXPECT_FALSE(scheduler_.LockstepReady());
  EXPECT_FALSE(scheduler_.CameraWanted(0));
}

TEST_F(SchedulerTest, SingleLockstepClientNeedsAStep) {
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(1);
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.ConsumeSteps();
  EXPECT_FALSE(scheduler_.LockstepReady());
}

TEST_F(SchedulerTest, TwoLockstepClientsReadyOnlyWhenBothStepped) {
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(2));
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(1);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(1);  // a second credit for 1 does not stand in for 2
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(2);
  EXPECT_TRUE(scheduler_.LockstepReady());
  // ConsumeSteps takes exactly one from each: 1 still holds one, 2 none.
  scheduler_.ConsumeSteps();
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(2);
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.ConsumeSteps();
  EXPECT_FALSE(scheduler_.LockstepReady());
}

TEST_F(SchedulerTest, CreditsAccumulate) {
  scheduler_.Subscribe(3, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(3));
  for (int i = 0; i < 5; ++i) scheduler_.AddStep(3);
  for (int i = 0; i < 5; ++i) {
    EXPECT_TRUE(scheduler_.LockstepReady()) << "round " << i;
    scheduler_.ConsumeSteps();
  }
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.ConsumeSteps();  // with no credits: stays at zero, no underflow
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(3);
  EXPECT_TRUE(scheduler_.LockstepReady());
}

// A link whose frames go into a real mailbox, as the transports' do.
class MailboxLink : public ClientLink {
 public:
  explicit MailboxLink(proto::Delivery delivery) { mailbox.Reset(delivery); }
  void OfferFrame(const FrameRef& frame) override { mailbox.Offer(frame); }
  void OfferReply(proto::Envelope) override {}
  FrameMailbox mailbox;
};

// A lockstep client that Steps but does not read holds the simulation back
// once its mailbox is full, however many credits it holds: the daemon renders
// and keeps at most limits::kLockstepFramesQueued frames for it.
TEST_F(SchedulerTest, AFullLockstepMailboxHoldsTheSimulationBack) {
  auto silent = std::make_shared<MailboxLink>(proto::DELIVERY_LOCKSTEP);
  auto reader = std::make_shared<MailboxLink>(proto::DELIVERY_LOCKSTEP);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, silent, silent->mailbox.gate());
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, reader, reader->mailbox.gate());
  for (std::size_t i = 0; i < FrameMailbox::kMaxLockstepBacklog; ++i) {
    scheduler_.AddStep(1);
    scheduler_.AddStep(2);
  }
  uint64_t advanced = 0;
  while (scheduler_.LockstepReady() && advanced < FrameMailbox::kMaxLockstepBacklog) {
    scheduler_.ConsumeSteps();
    scheduler_.Deliver(MakeFrame(++advanced, 0));
    reader->mailbox.Take();  // the reader keeps up
  }
  EXPECT_EQ(advanced, FrameMailbox::kLockstepCapacity) << "frames rendered for a client that never reads";
  EXPECT_LE(pool_.size(), FrameMailbox::kLockstepCapacity + 1);
  // It reads one: one more frame may be made, then it waits again.
  ASSERT_TRUE(silent->mailbox.Take());
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.ConsumeSteps();
  scheduler_.Deliver(MakeFrame(++advanced, 0));
  EXPECT_FALSE(scheduler_.LockstepReady());
  // Gone: it no longer holds anyone back.
  scheduler_.Remove(1);
  EXPECT_TRUE(scheduler_.LockstepReady());
}

// A full mailbox on a dead camera holds nobody back, like missing credits.
TEST_F(SchedulerTest, AFullMailboxOnADeadCameraDoesNotGate) {
  auto silent = std::make_shared<MailboxLink>(proto::DELIVERY_LOCKSTEP);
  scheduler_.Subscribe(1, 1, proto::DELIVERY_LOCKSTEP, kRgb, silent, silent->mailbox.gate());
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(2));
  for (std::size_t i = 0; i < FrameMailbox::kLockstepCapacity; ++i) silent->mailbox.Offer(MakeFrame(i + 1, 1));
  scheduler_.AddStep(1);
  scheduler_.AddStep(2);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.SetCameraDead(1, true);
  EXPECT_TRUE(scheduler_.LockstepReady());
}

TEST_F(SchedulerTest, NewestSubscribersNeverMakeItReadyButReceiveFrames) {
  auto newest = Link(1);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_NEWEST, kRgb, newest);
  scheduler_.AddStep(1);  // ignored for newest-frame subscribers
  scheduler_.AddStep(1);
  EXPECT_FALSE(scheduler_.LockstepReady());
  EXPECT_TRUE(scheduler_.CameraWanted(0));
  scheduler_.Deliver(MakeFrame(11, 0));
  EXPECT_EQ(newest->frames, std::vector<uint64_t>{11});

  // Alongside a lockstep client, only the lockstep client gates.
  auto lockstep = Link(2);
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, lockstep);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(2);
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.ConsumeSteps();
  scheduler_.Deliver(MakeFrame(12, 0));
  EXPECT_EQ(newest->frames, (std::vector<uint64_t>{11, 12}));
  EXPECT_EQ(lockstep->frames, std::vector<uint64_t>{12});
}

TEST_F(SchedulerTest, RemoveUnblocksTheOthers) {
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(2));
  scheduler_.AddStep(1);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.Remove(2);
  EXPECT_EQ(scheduler_.subscriber_count(), 1u);
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.Remove(1);
  EXPECT_EQ(scheduler_.subscriber_count(), 0u);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.Remove(42);  // unknown: harmless
  EXPECT_EQ(scheduler_.subscriber_count(), 0u);
}

TEST_F(SchedulerTest, RemovedClientGetsNoFrames) {
  auto a = Link(1);
  auto b = Link(2);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_NEWEST, kRgb, a);
  scheduler_.Subscribe(2, 0, proto::DELIVERY_NEWEST, kRgb, b);
  scheduler_.Remove(1);
  scheduler_.Deliver(MakeFrame(5, 0));
  EXPECT_TRUE(a->frames.empty());
  EXPECT_EQ(b->frames, std::vector<uint64_t>{5});
}

TEST_F(SchedulerTest, ResubscribeResetsCredits) {
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  scheduler_.AddStep(1);
  scheduler_.AddStep(1);
  EXPECT_TRUE(scheduler_.LockstepReady());
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  EXPECT_EQ(scheduler_.subscriber_count(), 1u);  // replaced, not added
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.AddStep(1);
  EXPECT_TRUE(scheduler_.LockstepReady());
}

TEST_F(SchedulerTest, ResubscribeAsNewestStopsGating) {
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(1));
  scheduler_.Subscribe(2, 0, proto::DELIVERY_LOCKSTEP, kRgb, Link(2));
  scheduler_.AddStep(1);
  EXPECT_FALSE(scheduler_.LockstepReady());
  scheduler_.Subscribe(2, 0, proto::DELIVERY_NEWEST, kRgb, Link(2));
  EXPECT_TRUE(scheduler_.LockstepReady());
}

TEST_F(SchedulerTest, ResubscribeReplacesTheLinkAndCamera) {
  auto old_link = Link(1);
  auto new_link = Link(1);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_NEWEST, kRgb, old_link);
  scheduler_.Subscribe(1, 1, proto::DELIVERY_NEWEST, kRgb, new_link);
  EXPECT_FALSE(scheduler_.CameraWanted(0));
  EXPECT_TRUE(scheduler_.CameraWanted(1));
  scheduler_.Deliver(MakeFrame(1, 1));
  EXPECT_TRUE(old_link->frames.empty());
  EXPECT_EQ(new_link->frames, std::vector<uint64_t>{1});
}

TEST_F(SchedulerTest, DeliverReachesOnlyThatCamerasSubscribersInClientIdOrder) {
  // Subscribed out of id order, across two cameras.
  auto c5 = Link(5);
  auto c2 = Link(2);
  auto c9 = Link(9);
  auto c1 = Link(1);
  scheduler_.Subscribe(5, 0, proto::DELIVERY_NEWEST, kRgb, c5);
  scheduler_.Subscribe(2, 1, proto::DELIVERY_NEWEST, kRgb, c2);
  scheduler_.Subscribe(9, 0, proto::DELIVERY_LOCKSTEP, kRgb, c9);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_NEWEST, kRgb, c1);
  EXPECT_TRUE(scheduler_.CameraWanted(0));
  EXPECT_TRUE(scheduler_.CameraWanted(1));
  EXPECT_FALSE(scheduler_.CameraWanted(2));

  scheduler_.Deliver(MakeFrame(100, 0));
  scheduler_.Deliver(MakeFrame(101, 1));
  scheduler_.Deliver(MakeFrame(102, 0));
  const std::vector<std::pair<int, uint64_t>> expected = {{1, 100}, {5, 100}, {9, 100}, {2, 101},
                                                          {1, 102}, {5, 102}, {9, 102}};
  EXPECT_EQ(delivery_log_, expected);
  EXPECT_EQ(c2->frames, std::vector<uint64_t>{101});
  EXPECT_EQ(c9->frames, (std::vector<uint64_t>{100, 102}));
}

TEST_F(SchedulerTest, DeliverSharesOneFrameWithoutCopying) {
  // Every link sees the same pooled object; after delivery (the links keep no
  // refs here) it goes back to the pool.
  struct AddressLink : ClientLink {
    void OfferFrame(const FrameRef& frame) override { addresses.push_back(&*frame); }
    void OfferReply(proto::Envelope) override {}  // the scheduler never answers
    std::vector<const Frame*> addresses;
  };
  auto a = std::make_shared<AddressLink>();
  auto b = std::make_shared<AddressLink>();
  scheduler_.Subscribe(1, 0, proto::DELIVERY_NEWEST, kRgb, a);
  scheduler_.Subscribe(2, 0, proto::DELIVERY_NEWEST, kRgb, b);
  {
    const FrameRef frame = MakeFrame(1, 0);
    scheduler_.Deliver(frame);
    ASSERT_EQ(a->addresses.size(), 1u);
    ASSERT_EQ(b->addresses.size(), 1u);
    EXPECT_EQ(a->addresses[0], &*frame);
    EXPECT_EQ(b->addresses[0], &*frame);
  }
  EXPECT_EQ(pool_.size(), 1u);
  Frame* again = nullptr;
  const FrameRef reused = pool_.Acquire(&again);
  EXPECT_EQ(again, a->addresses[0]);
}

TEST_F(SchedulerTest, AnObserverSeesFramesFirstAndSubscribersOnlyAtRelease) {
  auto observer = std::make_shared<RecordingLink>(0, &delivery_log_);
  auto client = Link(1);
  scheduler_.SetObserver(observer.get());
  EXPECT_FALSE(scheduler_.CameraWanted(1)) << "an observer subscribes to nothing";
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, client);
  EXPECT_EQ(scheduler_.CameraOf(1), 0u);
  EXPECT_EQ(scheduler_.CameraOf(2), std::nullopt);
  scheduler_.Deliver(MakeFrame(7, 0));
  scheduler_.Deliver(MakeFrame(7, 1));  // no subscriber: only the observer sees it
  EXPECT_EQ(observer->frames, (std::vector<uint64_t>{7, 7}));
  EXPECT_TRUE(client->frames.empty()) << "held until the log record is written";
  scheduler_.ReleaseFrames();
  EXPECT_EQ(client->frames, std::vector<uint64_t>{7});
  scheduler_.ReleaseFrames();  // nothing held: nothing delivered twice
  EXPECT_EQ(client->frames, std::vector<uint64_t>{7});
  scheduler_.SetObserver(nullptr);
  scheduler_.Deliver(MakeFrame(8, 0));
  EXPECT_EQ(client->frames, (std::vector<uint64_t>{7, 8}));
}

}  // namespace
}  // namespace sim4cv::session

namespace sim4cv::session {
namespace {

// Subscribe.max_fps: a rate-capped viewer wants (and is sent) a frame only
// when due by the wall clock BeginFrame gives, whatever the frame rate; the
// lockstep subscriber beside it gets every frame and steps as before.
TEST_F(SchedulerTest, RateCappedViewerIsRenderedForAndSentOnlyWhenDue) {
  using std::chrono::milliseconds;
  constexpr channels::ChannelSet kDepth = channels::Bit(proto::CHANNEL_DEPTH);
  auto stepper = Link(1);
  auto viewer = Link(2);
  scheduler_.Subscribe(1, 0, proto::DELIVERY_LOCKSTEP, kRgb, stepper);
  scheduler_.Subscribe(2, 1, proto::DELIVERY_NEWEST, kDepth, viewer, nullptr, 100'000'000);  // 10 fps
  std::chrono::steady_clock::time_point now{};
  int rendered_for_viewer = 0;
  for (uint64_t frame = 1; frame <= 50; ++frame) {  // 50 frames at 100 fps: half a second
    scheduler_.BeginFrame(now);
    EXPECT_TRUE(scheduler_.CameraWanted(0));
    if (scheduler_.CameraWanted(1)) {
      EXPECT_EQ(scheduler_.ChannelsWanted(1) & kDepth, kDepth);
      ++rendered_for_viewer;
      scheduler_.Deliver(MakeFrame(frame, 1));
    }
    scheduler_.Deliver(MakeFrame(frame, 0));
    now += milliseconds(10);
  }
  EXPECT_EQ(rendered_for_viewer, 5);
  EXPECT_EQ(viewer->frames, (std::vector<uint64_t>{1, 11, 21, 31, 41}));
  EXPECT_EQ(stepper->frames.size(), 50u);

  // After a pause (a lockstep simulation waiting for Steps) the cap starts
  // again from now: one frame, not a burst to catch up.
  now += milliseconds(2000);
  for (uint64_t frame = 51; frame <= 53; ++frame) {
    scheduler_.BeginFrame(now);
    if (scheduler_.CameraWanted(1)) scheduler_.Deliver(MakeFrame(frame, 1));
    now += milliseconds(10);
  }
  EXPECT_EQ(viewer->frames.back(), 51u);
  EXPECT_EQ(viewer->frames.size(), 6u);

  // A frame of its camera rendered for someone else is not sent before it is due either.
  auto other = Link(3);
  scheduler_.Subscribe(3, 1, proto::DELIVERY_NEWEST, kRgb, other);
  scheduler_.BeginFrame(now);
  EXPECT_EQ(scheduler_.ChannelsWanted(1) & kDepth, 0u);
  scheduler_.Deliver(MakeFrame(54, 1));
  EXPECT_EQ(other->frames.back(), 54u);
  EXPECT_EQ(viewer->frames.back(), 51u);
}

}  // namespace
}  // namespace sim4cv::session
