// Unit tests of the sim thread's reply path over shared memory
// (ShmClientLink::OfferReply): the real shm transport and the C++ ShmClient in
// one process, with a stand-in for the sim thread that offers replies through
// the client's link and frames through the ring's writer, as the scheduler
// does. Here "before the frame" means: once a client can read a frame, the
// replies offered before it are in its response ring.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <memory>
#include <string>

#include "server/transport/shm/shm_transport.h"
#include "sim4cv/shm_client.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/reply_path_support.h"

namespace sim4cv::test {
namespace {

class ShmReplyPathTest : public ::testing::Test {
 protected:
  // `max_clients` attachments; clients silent for `expiry_ms` are dropped.
  void Start(uint32_t max_clients = 4, uint32_t expiry_ms = 5000) {
    transport::ShmOptions options;
    options.name = "/sim4cv-unit-reply-path-" + std::to_string(getpid());
    options.width = kWidth;
    options.height = kHeight;
    options.max_clients = max_clients;
    options.expiry_ms = expiry_ms;
    transport_ = transport::MakeShmTransport(options);
    transport_->Start(sim_.context());
    ring_ = sim_.WaitForSubscriber().link;  // the ring's own subscription, posted by Start
    subscriber_ = Connect(client_);
  }
  void TearDown() override {
    if (transport_) transport_->Stop();  // also frees the name
  }

  // Opens `client`, says Hello and subscribes (newest); its link as the sim thread gets it.
  Subscriber Connect(ShmClient& client) {
    client.Open(transport_->info().address());
    client.Hello("reply-test");
    client.Subscribe(proto::DELIVERY_NEWEST);
    return sim_.WaitForSubscriber();
  }

  SimStandIn sim_;  // first: outlives the transport and every frame it holds
  std::unique_ptr<transport::Transport> transport_;
  std::shared_ptr<session::ClientLink> ring_;
  ShmClient client_;
  Subscriber subscriber_;
};

TEST_F(ShmReplyPathTest, RepliesFromTheSimThreadArriveInOrderAndBeforeLaterFrames) {
  Start();
  constexpr uint64_t kRounds = 3000;
  std::atomic<uint64_t> replies_seen{0};
  const auto sim = OfferRepliesThenFrames(sim_, *subscriber_.link, kRounds, replies_seen, ring_.get());
  uint64_t frames = 0, last_frame = 0;
  while (last_frame < kRounds) {
    ASSERT_TRUE(client_.WaitForFrame(last_frame, 5000ms)) << "after reply " << replies_seen << ", frame " << last_frame;
    FrameView view;
    ASSERT_TRUE(client_.AcquireNewest(view));
    last_frame = view.frame_id();
    ++frames;
    // Every reply offered before this frame is readable now.
    proto::Envelope reply;
    while (client_.ReceiveReply(reply, 0ms)) {
      ASSERT_TRUE(reply.has_state()) << reply.DebugString();
      ASSERT_EQ(reply.state().frame_id(), replies_seen + 1) << "a reply was lost or reordered";
      ++replies_seen;
    }
    ASSERT_GE(replies_seen.load(), last_frame) << "frame " << last_frame << " is readable before its reply";
  }
  EXPECT_EQ(replies_seen, kRounds);
  EXPECT_GT(frames, 0u);
  EXPECT_EQ(client_.responses_lost(), 0u);
}

TEST_F(ShmReplyPathTest, FatalErrorFromTheSimThreadIsSentThenTheSessionEnds) {
  Start();
  session::ClientLink& link = *subscriber_.link;
  link.OfferReply(MarkedReply(1));
  link.OfferReply(FatalError("the map could not be loaded"));
  link.OfferReply(MarkedReply(2));  // after the fatal Error: never written
  proto::Envelope reply;
  ASSERT_TRUE(client_.ReceiveReply(reply, 5000ms));
  EXPECT_EQ(reply.state().frame_id(), 1u);
  ASSERT_TRUE(client_.ReceiveReply(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.DebugString();
  EXPECT_TRUE(reply.error().fatal());
  EXPECT_EQ(reply.error().message(), "the map could not be loaded");
  // The shm thread ends the session without waiting for the client's next message.
  EXPECT_TRUE(sim_.WaitForDisconnect(subscriber_.client));
  EXPECT_FALSE(client_.ReceiveReply(reply, 100ms)) << reply.DebugString();
  // As after ClientProtocol's fatal Errors, the next message starts a new session.
  client_.Hello("reply-test-again");
  client_.Subscribe(proto::DELIVERY_NEWEST);
  EXPECT_NE(sim_.WaitForSubscriber().client, subscriber_.client);
}

TEST_F(ShmReplyPathTest, OfferingToAnExpiredClientIsHarmlessAndReachesNoOtherClient) {
  Start(/*max_clients=*/1, /*expiry_ms=*/300);
  // The client falls silent and is dropped; its only place is free again.
  ASSERT_TRUE(sim_.WaitForDisconnect(subscriber_.client));
  ShmClient next;
  next.Open(transport_->info().address());
  next.Hello("takes-the-place");  // the one place: the one the first client had
  subscriber_.link->OfferReply(MarkedReply(1));
  subscriber_.link->OfferFrame(sim_.MakeFrame(1));
  proto::Envelope reply;
  EXPECT_FALSE(next.ReceiveReply(reply, 100ms)) << "a reply to a gone client reached another: " << reply.DebugString();
  subscriber_.link.reset();
}

}  // namespace
}  // namespace sim4cv::test
