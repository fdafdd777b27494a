// Unit tests of the sim thread's reply path over TCP (TcpSession::OfferReply):
// the real TCP transport on loopback and the C++ client, with a stand-in for
// the sim thread that offers replies and frames through the client's link.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>

#include "server/transport/tcp/tcp_transport.h"
#include "sim4cv/client.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/reply_path_support.h"

namespace sim4cv::test {
namespace {

class TcpReplyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    transport_ = transport::MakeTcpTransport({});
    transport_->Start(sim_.context());
    subscriber_ = Connect(client_);
  }
  void TearDown() override { transport_->Stop(); }

  // Connects and subscribes `client` (newest frames of "uav"); its link as the sim thread gets it.
  Subscriber Connect(Client& client) {
    client.Connect("127.0.0.1", static_cast<uint16_t>(std::stoi(transport_->info().address())), "reply-test");
    client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST);
    return sim_.WaitForSubscriber();
  }

  SimStandIn sim_;  // first: outlives the transport and every frame it holds
  std::unique_ptr<transport::Transport> transport_;
  Client client_;
  Subscriber subscriber_;
};

TEST_F(TcpReplyTest, RepliesFromTheSimThreadArriveInOrderAndBeforeLaterFrames) {
  constexpr uint64_t kRounds = 3000;
  std::atomic<uint64_t> replies_seen{0};
  const auto sim = OfferRepliesThenFrames(sim_, *subscriber_.link, kRounds, replies_seen);
  uint64_t frames = 0, last_frame = 0;
  while (replies_seen < kRounds || last_frame < kRounds) {
    proto::Envelope envelope;
    ASSERT_TRUE(client_.ReceiveEnvelope(envelope, 5000ms)) << "after reply " << replies_seen << ", frame " << last_frame;
    if (envelope.has_state()) {
      ASSERT_EQ(envelope.state().frame_id(), replies_seen + 1) << "a reply was lost or reordered";
      ++replies_seen;
      continue;
    }
    ASSERT_TRUE(envelope.has_frame()) << envelope.DebugString();
    ASSERT_LE(envelope.frame().frame_id(), replies_seen.load())
        << "frame " << envelope.frame().frame_id() << " overtook the reply offered before it";
    EXPECT_EQ(envelope.frame().camera(), "uav");
    last_frame = envelope.frame().frame_id();
    ++frames;
  }
  EXPECT_GT(frames, 0u);
}

TEST_F(TcpReplyTest, FramesCarryTheCameraNameTheyWereRenderedWith) {
  subscriber_.link->OfferFrame(sim_.MakeFrame(1, "uav-renamed"));
  proto::Frame frame;
  ASSERT_TRUE(client_.ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.camera(), "uav-renamed") << "the name comes from the frame, not from the scene";
}

TEST_F(TcpReplyTest, FatalErrorFromTheSimThreadIsSentThenTheConnectionCloses) {
  session::ClientLink& link = *subscriber_.link;
  link.OfferReply(MarkedReply(1));
  link.OfferReply(FatalError("the map could not be loaded"));
  link.OfferReply(MarkedReply(2));       // after the fatal Error: never sent
  link.OfferFrame(sim_.MakeFrame(1));  // nor is this
  proto::Envelope envelope;
  ASSERT_TRUE(client_.ReceiveEnvelope(envelope, 5000ms));
  EXPECT_EQ(envelope.state().frame_id(), 1u);
  ASSERT_TRUE(client_.ReceiveEnvelope(envelope, 5000ms));
  ASSERT_TRUE(envelope.has_error()) << envelope.DebugString();
  EXPECT_TRUE(envelope.error().fatal());
  EXPECT_EQ(envelope.error().message(), "the map could not be loaded");
  EXPECT_THROW(client_.ReceiveEnvelope(envelope, 5000ms), ConnectionError) << "the connection stays open";
  EXPECT_TRUE(sim_.WaitForDisconnect(subscriber_.client));
}

TEST_F(TcpReplyTest, OfferingToAClosedClientIsHarmless) {
  client_.Close();
  ASSERT_TRUE(sim_.WaitForDisconnect(subscriber_.client));
  subscriber_.link->OfferReply(MarkedReply(1));
  subscriber_.link->OfferFrame(sim_.MakeFrame(1));
  // The sim thread may hold the link longest: the session goes with it, and
  // so must every frame it was offered (the pool aborts at the end otherwise).
  subscriber_.link.reset();

  // The next client hears only its own replies.
  Client next;
  const Subscriber second = Connect(next);
  second.link->OfferReply(MarkedReply(2));
  proto::Envelope envelope;
  ASSERT_TRUE(next.ReceiveEnvelope(envelope, 5000ms));
  EXPECT_EQ(envelope.state().frame_id(), 2u);
}

}  // namespace
}  // namespace sim4cv::test
