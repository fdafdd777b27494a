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

class TcpReplyTest : public SocketReplyTest<Client> {
 protected:
  std::unique_ptr<transport::Transport> MakeTransport() override { return transport::MakeTcpTransport({}); }
};

TEST_F(TcpReplyTest, RepliesFromTheSimThreadArriveInOrderAndBeforeLaterFrames) {
  ExpectRepliesInOrderBeforeLaterFrames(sim_, *subscriber_.link, client_, 3000);
}

TEST_F(TcpReplyTest, FramesCarryTheCameraNameTheyWereRenderedWith) { ExpectFramesCarryTheirCameraName(); }

TEST_F(TcpReplyTest, FatalErrorFromTheSimThreadIsSentThenTheConnectionCloses) {
  ExpectFatalErrorEndsTheClient();
  proto::Envelope envelope;
  EXPECT_THROW(client_.ReceiveEnvelope(envelope, 5000ms), ConnectionError) << "the connection stays open";
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
