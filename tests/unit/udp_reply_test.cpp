// Unit tests of the sim thread's reply path over UDP (UdpPeer::OfferReply):
// the real UDP transport on loopback and the C++ UDP client, with a stand-in
// for the sim thread that offers replies and frames through the client's link.
#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <string>

#include "server/transport/udp/udp_transport.h"
#include "sim4cv/udp_client.h"
#include "tests/support/no_warnings.h"
#include "tests/unit/reply_path_support.h"

namespace sim4cv::test {
namespace {

constexpr uint32_t kExpiryMs = 400;

class UdpReplyTest : public SocketReplyTest<UdpClient> {
 protected:
  std::unique_ptr<transport::Transport> MakeTransport() override {
    transport::UdpOptions options;
    options.expiry_ms = kExpiryMs;
    return transport::MakeUdpTransport(options);
  }
};

TEST_F(UdpReplyTest, RepliesFromTheSimThreadArriveInOrderAndBeforeLaterFrames) {
  // The client only reads for the whole run, which takes longer than the
  // short expiry on a loaded machine: its keep-alives keep it registered
  // (the default 1 s interval is for the daemon's default 5 s expiry).
  client_.set_keepalive_interval(std::chrono::milliseconds(kExpiryMs / 4));
  ExpectRepliesInOrderBeforeLaterFrames(sim_, *subscriber_.link, client_, 3000);
}

TEST_F(UdpReplyTest, FramesCarryTheCameraNameTheyWereRenderedWith) { ExpectFramesCarryTheirCameraName(); }

TEST_F(UdpReplyTest, FatalErrorFromTheSimThreadIsSentThenThePeerIsUnregistered) {
  ExpectFatalErrorEndsTheClient();
  proto::Envelope envelope;
  EXPECT_FALSE(client_.ReceiveEnvelope(envelope, 200ms)) << envelope.DebugString();
  try {
    client_.GetStats(1000ms);
    ADD_FAILURE() << "the address is still registered";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_NOT_HANDSHAKEN) << error.what();
  }
}

TEST_F(UdpReplyTest, AStrayWelcomeAfterConnectIsDropped) {
  // On a slow machine Connect repeats its Hello before the first Welcome comes
  // back, and the daemon answers each: the second Welcome arrives after Connect.
  proto::Envelope welcome;
  welcome.mutable_welcome()->set_scene_name("default");
  subscriber_.link->OfferReply(welcome);
  subscriber_.link->OfferFrame(sim_.MakeFrame(1));
  proto::Frame frame;
  ASSERT_TRUE(client_.ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), 1u);
  proto::Envelope envelope;
  EXPECT_FALSE(client_.ReceiveEnvelope(envelope, 200ms)) << "still queued: " << envelope.ShortDebugString();
}

TEST_F(UdpReplyTest, OfferingToAnExpiredClientIsHarmless) {
  // The client falls silent; its registration lapses.
  ASSERT_TRUE(sim_.WaitForDisconnect(subscriber_.client, std::chrono::milliseconds(10 * kExpiryMs)));
  subscriber_.link->OfferReply(MarkedReply(1));
  subscriber_.link->OfferFrame(sim_.MakeFrame(1));
  proto::Envelope envelope;
  EXPECT_FALSE(client_.ReceiveEnvelope(envelope, 200ms)) << envelope.DebugString();
  subscriber_.link.reset();  // the session goes, and every frame it was offered (the pool checks at the end)

  // The next client hears only its own replies.
  UdpClient next;
  const Subscriber second = Connect(next);
  second.link->OfferReply(MarkedReply(2));
  ASSERT_TRUE(next.ReceiveEnvelope(envelope, 5000ms));
  EXPECT_EQ(envelope.state().frame_id(), 2u);
}

}  // namespace
}  // namespace sim4cv::test
