// Unit tests of the session rules every transport shares
// (server/session/client_session.*): a reply offered before a frame goes
// first, frames of a replaced subscription are skipped, nothing offered after
// StopOffers or Close is kept, Close tells the sim thread once, and every
// offer wakes the transport.
#include "server/session/client_session.h"

#include <gtest/gtest.h>

#include <atomic>
#include <variant>
#include <vector>

#include "protocol/framing.h"
#include "server/sim/scene.h"
#include "tests/support/no_warnings.h"
#include "tests/support/world_info.h"

namespace sim4cv::session {
namespace {

using Outcome = ClientProtocol::Outcome;

class ClientSessionTest : public ::testing::Test {
 protected:
  ClientSessionTest() : context_{scene_, proto::SIM_MODE_LOCKSTEP, Welcome(), world_, commands_, latest_state_,
                                 1u << 20, counters_, "", ""} {
    world_.Publish(testing::FirstCameraWorld(scene_, {{"second", 16}}));
    session_ = ClientSession::Create(7, context_, [this] { ++wakes_; });
  }
  ~ClientSessionTest() override { session_->Close(false); }

  static proto::Welcome Welcome() {
    proto::Welcome welcome;
    welcome.set_protocol_version(wire::kProtocolVersion);
    welcome.set_mode(proto::SIM_MODE_LOCKSTEP);
    return welcome;
  }

  void Send(const proto::Envelope& request) { ASSERT_EQ(session_->Handle(request, reply_), Outcome::kReply); }
  void HandshakeAndSubscribe(const std::string& camera, proto::Delivery delivery = proto::DELIVERY_LOCKSTEP) {
    proto::Envelope hello;
    hello.mutable_hello()->set_protocol_version(wire::kProtocolVersion);
    hello.mutable_hello()->set_client_name("unit");
    Send(hello);
    proto::Envelope subscribe;
    subscribe.mutable_subscribe()->set_camera(camera);
    subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_RGB);
    subscribe.mutable_subscribe()->set_delivery(delivery);
    Send(subscribe);
    ASSERT_TRUE(reply_.has_subscribed()) << reply_.ShortDebugString();
  }
  FrameRef MakeFrame(uint64_t id, uint32_t camera = 0) {
    Frame* frame = nullptr;
    FrameRef ref = frames_.Acquire(&frame);
    frame->frame_id = id;
    frame->camera_index = camera;
    return ref;
  }
  static proto::Envelope ErrorReply(const std::string& message, bool fatal = false) {
    proto::Envelope reply;
    ClientProtocol::Refuse(proto::ERROR_CODE_INVALID_STATE, message, fatal, reply);
    return reply;
  }
  std::size_t Disconnects() {
    std::vector<Command> drained;
    commands_.Drain(drained);
    std::size_t count = 0;
    for (const Command& c : drained) count += std::holds_alternative<DisconnectCommand>(c.body);
    return count;
  }

  const sim::Scene scene_ = sim::DefaultScene(320, 180);
  WorldDirectory world_;
  CommandQueue commands_;
  StatePool state_pool_;
  LatestState latest_state_;
  Counters counters_;
  ServerContext context_;
  FramePool frames_;  // outlives the session's refs
  std::shared_ptr<ClientSession> session_;
  std::atomic<int> wakes_{0};
  proto::Envelope reply_;
};

TEST_F(ClientSessionTest, AReplyOfferedBeforeAFrameGoesFirst) {
  HandshakeAndSubscribe("uav");
  session_->OfferReply(ErrorReply("first"));
  session_->OfferFrame(MakeFrame(1));
  EXPECT_EQ(wakes_, 2);
  EXPECT_FALSE(session_->NextFrame()) << "the frame must wait for the reply offered before it";
  std::vector<proto::Envelope> replies;
  session_->TakeReplies(replies);
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error().message(), "first");
  const FrameRef frame = session_->NextFrame();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->frame_id, 1u);
  EXPECT_FALSE(session_->NextFrame());
}

// On request, frames wait (the newest replacing the rest) until a NextFrame
// asks; one request takes one frame, and one asked for before any is
// rendered takes the next one.
TEST_F(ClientSessionTest, OnRequestDeliverySendsOneFrameForEachRequest) {
  HandshakeAndSubscribe("uav", proto::DELIVERY_ON_REQUEST);
  proto::Envelope next;
  next.mutable_next_frame();
  session_->OfferFrame(MakeFrame(1));
  session_->OfferFrame(MakeFrame(2));
  EXPECT_FALSE(session_->NextFrame()) << "nobody asked";
  ASSERT_EQ(session_->Handle(next, reply_), Outcome::kNoReply);
  ASSERT_EQ(session_->Handle(next, reply_), Outcome::kNoReply);  // a repeated request asks for nothing more
  FrameRef frame = session_->NextFrame();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->frame_id, 2u) << "the newest";
  EXPECT_EQ(session_->dropped(), 1u) << "frame 1, which nobody asked for";
  session_->OfferFrame(MakeFrame(3));
  EXPECT_FALSE(session_->NextFrame()) << "one request, one frame";
  ASSERT_EQ(session_->Handle(next, reply_), Outcome::kNoReply);
  frame = session_->NextFrame();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->frame_id, 3u);
  ASSERT_EQ(session_->Handle(next, reply_), Outcome::kNoReply);
  EXPECT_FALSE(session_->NextFrame()) << "already sent the newest: the request waits for the next";
  session_->OfferFrame(MakeFrame(4));
  frame = session_->NextFrame();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->frame_id, 4u);
}

TEST_F(ClientSessionTest, FramesOfAReplacedSubscriptionAreSkipped) {
  HandshakeAndSubscribe("uav");
  session_->OfferFrame(MakeFrame(1, /*camera=*/0));
  HandshakeAndSubscribe("second");  // a new subscription: camera 1
  session_->OfferFrame(MakeFrame(2, /*camera=*/0));  // rendered before the switch took effect
  session_->OfferFrame(MakeFrame(3, /*camera=*/1));
  const FrameRef frame = session_->NextFrame();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->frame_id, 3u);
}

TEST_F(ClientSessionTest, NothingIsKeptAfterStopOffersAndCloseTellsTheSimThreadOnce) {
  HandshakeAndSubscribe("uav");
  Disconnects();
  session_->StopOffers();
  session_->OfferReply(ErrorReply("late"));
  session_->OfferFrame(MakeFrame(1));
  EXPECT_EQ(wakes_, 0);
  EXPECT_FALSE(session_->replies_pending());
  EXPECT_FALSE(session_->NextFrame());
  session_->Close(true);
  session_->Close(true);
  EXPECT_EQ(Disconnects(), 1u);
}

TEST_F(ClientSessionTest, AFrameDoneLetsALockstepClientStepAgain) {
  HandshakeAndSubscribe("uav");
  proto::Envelope step;
  step.mutable_step();
  for (std::size_t i = 0; i < limits::kMaxOutstandingSteps; ++i) {
    ASSERT_EQ(session_->Handle(step, reply_), Outcome::kNoReply);
  }
  EXPECT_EQ(session_->Handle(step, reply_), Outcome::kReply) << "one Step past the limit is refused";
  EXPECT_NE(reply_.error().message().find("Step"), std::string::npos) << reply_.error().message();
  session_->FrameDone();
  EXPECT_EQ(session_->Handle(step, reply_), Outcome::kNoReply);
}

}  // namespace
}  // namespace sim4cv::session
