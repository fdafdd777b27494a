// Unit tests of the per-connection protocol rules (server/session/client_protocol.*):
// every refusal, and the Commands and replies of every accepted request.
#include "server/session/client_protocol.h"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <variant>
#include <vector>

#include "protocol/channels.h"
#include "protocol/framing.h"
#include "server/common/limits.h"
#include "tests/support/no_warnings.h"
#include "tests/support/world_info.h"

namespace sim4cv::session {
namespace {

using Outcome = ClientProtocol::Outcome;
constexpr ClientId kClient = 7;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

class NullLink : public ClientLink {
 public:
  void OfferFrame(const FrameRef& frame) override { offered.push_back(frame->frame_id); }
  void OfferReply(proto::Envelope reply) override { replies.push_back(std::move(reply)); }
  std::vector<uint64_t> offered;
  std::vector<proto::Envelope> replies;
};

proto::Welcome MakeWelcome(proto::SimMode mode) {
  proto::Welcome welcome;
  welcome.set_protocol_version(wire::kProtocolVersion);
  welcome.set_server_version("test");
  welcome.set_mode(mode);
  welcome.set_physics_hz(240);
  welcome.set_frame_hz(30);
  return welcome;
}

proto::Envelope Hello(uint32_t version = wire::kProtocolVersion, const std::string& name = "unit") {
  proto::Envelope e;
  e.mutable_hello()->set_protocol_version(version);
  e.mutable_hello()->set_client_name(name);
  return e;
}

proto::Envelope Subscribe(const std::string& camera, std::vector<int> channels,
                          proto::Delivery delivery = proto::DELIVERY_NEWEST, bool with_state = false) {
  proto::Envelope e;
  proto::Subscribe* s = e.mutable_subscribe();
  s->set_camera(camera);
  for (int c : channels) s->add_channels(static_cast<proto::Channel>(c));
  s->set_delivery(delivery);
  s->set_with_state(with_state);
  return e;
}

proto::Envelope Step() {
  proto::Envelope e;
  e.mutable_step();
  return e;
}

proto::Envelope Controls(uint32_t entity, float steering, float throttle, float brake) {
  proto::Envelope e;
  proto::Controls* c = e.mutable_controls();
  c->set_entity_id(entity);
  c->set_steering(steering);
  c->set_throttle(throttle);
  c->set_brake(brake);
  return e;
}

proto::Envelope Tracker(uint64_t frame_id, float x, float y, float w, float h, float confidence) {
  proto::Envelope e;
  proto::TrackerOutput* t = e.mutable_tracker_output();
  t->set_frame_id(frame_id);
  t->mutable_box()->set_x(x);
  t->mutable_box()->set_y(y);
  t->mutable_box()->set_width(w);
  t->mutable_box()->set_height(h);
  t->set_confidence(confidence);
  return e;
}

proto::Envelope GetState() {
  proto::Envelope e;
  e.mutable_get_state();
  return e;
}

class ClientProtocolTest : public ::testing::Test {
 protected:
  explicit ClientProtocolTest(proto::SimMode mode = proto::SIM_MODE_LOCKSTEP)
      : context_{scene_, mode, MakeWelcome(mode), world_, commands_, latest_state_, 1u << 20, counters_, "", ""},
        protocol_(kClient, context_, link_, &mailbox_) {
    // What the sim thread publishes: here only the scene's first camera.
    world_.Publish(testing::FirstCameraWorld(scene_));
  }

  Outcome Send(const proto::Envelope& request) { return protocol_.Handle(request, reply_); }

  void Handshake() {
    ASSERT_EQ(Send(Hello()), Outcome::kReply);
    ASSERT_TRUE(reply_.has_welcome());
    Drain();
  }

  std::vector<Command> Drain() {
    std::vector<Command> out;
    commands_.Drain(out);
    return out;
  }

  // Asserts the last reply is an Error with this code/fatality whose message
  // holds every one of `parts`, and that no Command was posted.
  void ExpectError(Outcome outcome, proto::ErrorCode code, bool fatal, std::vector<std::string> parts) {
    EXPECT_EQ(outcome, fatal ? Outcome::kReplyAndClose : Outcome::kReply);
    ASSERT_TRUE(reply_.has_error()) << reply_.DebugString();
    EXPECT_EQ(reply_.error().code(), code)
        << proto::ErrorCode_Name(reply_.error().code()) << ": " << reply_.error().message();
    EXPECT_EQ(reply_.error().fatal(), fatal);
    for (const auto& part : parts) {
      EXPECT_NE(reply_.error().message().find(part), std::string::npos)
          << "message '" << reply_.error().message() << "' lacks '" << part << "'";
    }
    EXPECT_TRUE(Drain().empty()) << "a refused request posted a Command";
  }

  const sim::Scene scene_ = sim::DefaultScene(320, 180);
  WorldDirectory world_;
  CommandQueue commands_;
  StatePool state_pool_;  // outlives latest_state_'s ref
  LatestState latest_state_;
  Counters counters_;
  ServerContext context_;
  std::shared_ptr<NullLink> link_ = std::make_shared<NullLink>();
  FramePool frame_pool_;  // outlives mailbox_'s refs
  FrameMailbox mailbox_;
  ClientProtocol protocol_;
  proto::Envelope reply_;
};

class RealtimeClientProtocolTest : public ClientProtocolTest {
 protected:
  RealtimeClientProtocolTest() : ClientProtocolTest(proto::SIM_MODE_REALTIME) {}
};

// ---- Handshake -----------------------------------------------------------

TEST_F(ClientProtocolTest, EmptyEnvelopeIsFatal) {
  ExpectError(Send(proto::Envelope()), proto::ERROR_CODE_UNEXPECTED_MESSAGE, true, {"carries no message"});
  // Also after the handshake.
  Handshake();
  ExpectError(Send(proto::Envelope()), proto::ERROR_CODE_UNEXPECTED_MESSAGE, true, {"carries no message"});
}

TEST_F(ClientProtocolTest, RequestBeforeHelloIsFatal) {
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB})), proto::ERROR_CODE_NOT_HANDSHAKEN, true,
              {"first message must be Hello", "got field 3"});
  ExpectError(Send(Step()), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 5"});
  ExpectError(Send(Controls(1, 0, 0, 0)), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 8"});
  ExpectError(Send(Tracker(1, 0, 0, 1, 1, 0.5f)), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 7"});
  ExpectError(Send(GetState()), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 9"});
  proto::Envelope frame;
  frame.mutable_frame()->set_frame_id(1);
  ExpectError(Send(frame), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 6"});
  EXPECT_FALSE(protocol_.subscribed());
}

TEST_F(ClientProtocolTest, HelloIsWelcomedWithTheClientId) {
  ASSERT_EQ(Send(Hello(wire::kProtocolVersion, "tracker-A")), Outcome::kReply);
  ASSERT_TRUE(reply_.has_welcome());
  EXPECT_EQ(reply_.welcome().client_id(), kClient);
  EXPECT_EQ(reply_.welcome().protocol_version(), wire::kProtocolVersion);
  EXPECT_EQ(reply_.welcome().scene_name(), "default");
  EXPECT_EQ(reply_.welcome().server_version(), "test");
  ASSERT_EQ(reply_.welcome().cameras_size(), 1);
  EXPECT_EQ(reply_.welcome().cameras(0).name(), "uav");
  EXPECT_EQ(reply_.welcome().mode(), proto::SIM_MODE_LOCKSTEP);
  EXPECT_EQ(protocol_.client_name(), "tracker-A");
  EXPECT_EQ(protocol_.client(), kClient);
  // The shared Welcome keeps client_id 0 for the next connection.
  EXPECT_EQ(context_.welcome.client_id(), 0u);
  EXPECT_TRUE(Drain().empty());
}

TEST_F(ClientProtocolTest, WrongVersionNamesBothVersions) {
  ExpectError(Send(Hello(2)), proto::ERROR_CODE_VERSION_MISMATCH, true,
              {"client speaks protocol version 2", "this server speaks version 1"});
  ExpectError(Send(Hello(0)), proto::ERROR_CODE_VERSION_MISMATCH, true, {"version 0", "version 1"});
  // Still not handshaken.
  ExpectError(Send(GetState()), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {});
}

TEST_F(ClientProtocolTest, SecondHelloIsRefusedButNotFatal) {
  Handshake();
  ExpectError(Send(Hello(wire::kProtocolVersion, "again")), proto::ERROR_CODE_INVALID_STATE, false,
              {"already accepted", "only once"});
  EXPECT_EQ(protocol_.client_name(), "unit");
  // A second Hello with a wrong version is still just "already accepted".
  ExpectError(Send(Hello(9)), proto::ERROR_CODE_INVALID_STATE, false, {"already accepted"});
}

TEST_F(ClientProtocolTest, ServerOnlyMessagesAreFatal) {
  Handshake();
  std::vector<proto::Envelope> server_only(7);
  server_only[0].mutable_welcome()->set_client_id(1);
  server_only[1].mutable_subscribed()->set_camera("uav");
  server_only[2].mutable_frame()->set_frame_id(3);
  server_only[3].mutable_state()->set_frame_id(4);
  server_only[4].mutable_error()->set_message("x");
  server_only[5].mutable_frame_chunk()->set_frame_id(5);
  server_only[6].mutable_stats();
  const char* fields[] = {"field 2 ", "field 4 ", "field 6 ", "field 10 ", "field 11 ", "field 12 ", "field 14 "};
  for (std::size_t i = 0; i < server_only.size(); ++i) {
    SCOPED_TRACE(fields[i]);
    ExpectError(Send(server_only[i]), proto::ERROR_CODE_UNEXPECTED_MESSAGE, true, {fields[i], "only the server sends"});
  }
}

// ---- Subscribe -----------------------------------------------------------

TEST_F(ClientProtocolTest, UnknownCameraListsTheScenesCameras) {
  Handshake();
  ExpectError(Send(Subscribe("front", {proto::CHANNEL_RGB})), proto::ERROR_CODE_UNKNOWN_CAMERA, false,
              {"no camera named 'front'", "'uav'"});
  ExpectError(Send(Subscribe("", {proto::CHANNEL_RGB})), proto::ERROR_CODE_UNKNOWN_CAMERA, false, {"''", "'uav'"});
  EXPECT_FALSE(protocol_.subscribed());
}

TEST_F(ClientProtocolTest, EmptyChannelsAreRefused) {
  Handshake();
  ExpectError(Send(Subscribe("uav", {})), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"Subscribe.channels is empty"});
}

TEST_F(ClientProtocolTest, OutOfRangeChannelsAreRefused) {
  Handshake();
  // The message lists every channel of the table by number and name, then BOXES.
  std::vector<std::string> parts = {
      "Subscribe.channels holds 0", "which is no channel this daemon serves",
      "valid channels are 1 (RGB), 2 (DEPTH), 3 (MASK), 5 (SEMANTIC), 6 (NORMALS), 7 (FLOW), ", "), and 4 (BOXES)"};
  for (const channels::ChannelInfo& info : channels::kPixelChannels) {
    std::string name(info.name);
    for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    parts.push_back(std::to_string(info.id) + " (" + name + "), ");
  }
  ExpectError(Send(Subscribe("uav", {0})), proto::ERROR_CODE_INVALID_ARGUMENT, false, parts);
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB, 99})), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"holds 99"});
  const int past_the_table = proto::Channel_ARRAYSIZE;  // one past the proto's largest Channel value
  ExpectError(Send(Subscribe("uav", {past_the_table})), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"holds " + std::to_string(past_the_table)});
  ExpectError(Send(Subscribe("uav", {-1})), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"holds -1"});
}

TEST_F(ClientProtocolTest, DuplicateChannelIsRefused) {
  Handshake();
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_RGB})),
              proto::ERROR_CODE_INVALID_ARGUMENT, false, {"lists CHANNEL_RGB twice"});
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_BOXES, proto::CHANNEL_BOXES})), proto::ERROR_CODE_INVALID_ARGUMENT,
              false, {"CHANNEL_BOXES twice"});
}

TEST_F(ClientProtocolTest, UnspecifiedOrUnknownDeliveryIsRefused) {
  Handshake();
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_UNSPECIFIED)),
              proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"Subscribe.delivery is 0", "DELIVERY_LOCKSTEP (1), DELIVERY_NEWEST (2) or DELIVERY_ON_REQUEST (3)"});
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB}, static_cast<proto::Delivery>(7))),
              proto::ERROR_CODE_INVALID_ARGUMENT, false, {"Subscribe.delivery is 7"});
}

// Subscribe.max_fps: a period for the sim thread's scheduler, echoed in
// Subscribed; out of range or on a lockstep subscription, an Error naming it.
TEST_F(ClientProtocolTest, MaxFpsCapsNewestSubscriptionsOnly) {
  Handshake();
  proto::Envelope capped = Subscribe("uav", {proto::CHANNEL_RGB});
  capped.mutable_subscribe()->set_max_fps(30);
  ASSERT_EQ(Send(capped), Outcome::kReply);
  EXPECT_EQ(reply_.subscribed().max_fps(), 30);
  const std::vector<Command> commands = Drain();
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(std::get<SubscribeCommand>(commands[0].body).min_interval_ns, 33'333'333);
  for (const double bad : {-1.0, 1001.0, std::nan("")}) {
    capped.mutable_subscribe()->set_max_fps(bad);
    ExpectError(Send(capped), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"Subscribe.max_fps is", "1000"});
  }
  proto::Envelope lockstep = Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  lockstep.mutable_subscribe()->set_max_fps(30);
  ExpectError(Send(lockstep), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"max_fps", "lockstep subscriber"});
}

TEST_F(RealtimeClientProtocolTest, LockstepDeliveryInRealtimeModeIsRefused) {
  Handshake();
  ExpectError(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP)), proto::ERROR_CODE_INVALID_STATE,
              false, {"--mode lockstep", "realtime", "DELIVERY_NEWEST"});
  EXPECT_FALSE(protocol_.subscribed());
  // Newest is fine in realtime mode.
  EXPECT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST)), Outcome::kReply);
  EXPECT_TRUE(reply_.has_subscribed());
}

TEST_F(ClientProtocolTest, SubscribeEchoesAndPostsTheCommand) {
  Handshake();
  // Something waiting in the mailbox from an earlier subscription.
  {
    Frame* f = nullptr;
    FrameRef ref = frame_pool_.Acquire(&f);
    f->frame_id = 99;
    mailbox_.Offer(ref);
    mailbox_.Offer(ref);
    ASSERT_EQ(mailbox_.dropped(), 1u);
  }
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_MASK, proto::CHANNEL_DEPTH, proto::CHANNEL_RGB, proto::CHANNEL_BOXES},
                           proto::DELIVERY_LOCKSTEP, true)),
            Outcome::kReply);
  ASSERT_TRUE(reply_.has_subscribed()) << reply_.DebugString();
  const proto::Subscribed& subscribed = reply_.subscribed();
  EXPECT_EQ(subscribed.camera(), "uav");
  ASSERT_EQ(subscribed.channels_size(), 4);
  EXPECT_EQ(subscribed.channels(0), proto::CHANNEL_MASK);
  EXPECT_EQ(subscribed.channels(1), proto::CHANNEL_DEPTH);
  EXPECT_EQ(subscribed.channels(2), proto::CHANNEL_RGB);
  EXPECT_EQ(subscribed.channels(3), proto::CHANNEL_BOXES);
  EXPECT_EQ(subscribed.delivery(), proto::DELIVERY_LOCKSTEP);
  EXPECT_EQ(protocol_.subscription().SerializeAsString(), subscribed.SerializeAsString());
  EXPECT_TRUE(protocol_.subscribed());
  EXPECT_TRUE(protocol_.with_state());
  EXPECT_EQ(protocol_.camera_index(), 0u);
  // The mailbox was reset for the new subscription.
  EXPECT_FALSE(mailbox_.Take());
  EXPECT_EQ(mailbox_.dropped(), 0u);

  const std::vector<Command> commands = Drain();
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(commands[0].client, kClient);
  const auto* subscribe = std::get_if<SubscribeCommand>(&commands[0].body);
  ASSERT_NE(subscribe, nullptr);
  EXPECT_EQ(subscribe->camera_index, 0u);
  EXPECT_EQ(subscribe->delivery, proto::DELIVERY_LOCKSTEP);
  EXPECT_EQ(subscribe->link.get(), link_.get());
}

TEST_F(ClientProtocolTest, ResubscribeReplacesTheSubscription) {
  Handshake();
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH}, proto::DELIVERY_LOCKSTEP, true)),
            Outcome::kReply);
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_NEWEST, false)), Outcome::kReply);
  ASSERT_TRUE(reply_.has_subscribed());
  ASSERT_EQ(reply_.subscribed().channels_size(), 1);
  EXPECT_EQ(reply_.subscribed().channels(0), proto::CHANNEL_BOXES);
  EXPECT_EQ(reply_.subscribed().delivery(), proto::DELIVERY_NEWEST);
  EXPECT_FALSE(protocol_.with_state());
  const auto commands = Drain();
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(std::get<SubscribeCommand>(commands[1].body).delivery, proto::DELIVERY_NEWEST);
  // A refused Subscribe leaves the current one in force.
  ExpectError(Send(Subscribe("uav", {})), proto::ERROR_CODE_INVALID_ARGUMENT, false, {});
  EXPECT_TRUE(protocol_.subscribed());
  EXPECT_EQ(protocol_.subscription().channels_size(), 1);
}

// ---- Step ----------------------------------------------------------------

TEST_F(ClientProtocolTest, StepWithoutLockstepSubscriptionIsRefused) {
  Handshake();
  ExpectError(Send(Step()), proto::ERROR_CODE_INVALID_STATE, false, {"Step needs a lockstep subscription"});
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST)), Outcome::kReply);
  Drain();
  ExpectError(Send(Step()), proto::ERROR_CODE_INVALID_STATE, false, {"DELIVERY_LOCKSTEP"});
}

TEST_F(ClientProtocolTest, NextFrameWithoutAnOnRequestSubscriptionIsRefused) {
  Handshake();
  proto::Envelope next;
  next.mutable_next_frame();
  ExpectError(Send(next), proto::ERROR_CODE_INVALID_STATE, false,
              {"NextFrame needs an on-request subscription; send Subscribe with DELIVERY_ON_REQUEST first"});
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST)), Outcome::kReply);
  Drain();
  ExpectError(Send(next), proto::ERROR_CODE_INVALID_STATE, false, {"DELIVERY_ON_REQUEST"});
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_ON_REQUEST)), Outcome::kReply);
  Drain();
  EXPECT_EQ(Send(next), Outcome::kNoReply) << "the frame is the answer";
  EXPECT_TRUE(protocol_.frame_requested());
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_ON_REQUEST)), Outcome::kReply);
  EXPECT_FALSE(protocol_.frame_requested()) << "a new subscription starts with no request";
}

TEST_F(ClientProtocolTest, StepPostsAStepCommand) {
  Handshake();
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP)), Outcome::kReply);
  Drain();
  reply_.mutable_welcome();  // Handle clears the reply even when it has nothing to say
  EXPECT_EQ(Send(Step()), Outcome::kNoReply);
  EXPECT_EQ(reply_.kind_case(), proto::Envelope::KIND_NOT_SET);
  const auto commands = Drain();
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(commands[0].client, kClient);
  EXPECT_TRUE(std::holds_alternative<StepCommand>(commands[0].body));
}

TEST_F(ClientProtocolTest, TooManyOutstandingStepsAreRefused) {
  Handshake();
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP)), Outcome::kReply);
  Drain();
  const std::size_t limit = FrameMailbox::kMaxLockstepBacklog;
  for (std::size_t i = 0; i < limit; ++i) ASSERT_EQ(Send(Step()), Outcome::kNoReply) << i;
  EXPECT_EQ(Drain().size(), limit);
  ExpectError(Send(Step()), proto::ERROR_CODE_INVALID_STATE, false,
              {std::to_string(limit) + " Steps are already waiting", "limit " + std::to_string(limit)});
  // One frame delivered: one more Step allowed, then refused again.
  protocol_.OnFrameSent();
  EXPECT_EQ(Send(Step()), Outcome::kNoReply);
  EXPECT_EQ(Drain().size(), 1u);
  ExpectError(Send(Step()), proto::ERROR_CODE_INVALID_STATE, false, {"already waiting"});
  // Re-subscribing starts the count afresh.
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP)), Outcome::kReply);
  Drain();
  EXPECT_EQ(Send(Step()), Outcome::kNoReply);
}

TEST_F(ClientProtocolTest, OnFrameSentNeverUnderflows) {
  Handshake();
  ASSERT_EQ(Send(Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP)), Outcome::kReply);
  Drain();
  for (int i = 0; i < 10; ++i) protocol_.OnFrameSent();  // newest-style extra frames
  for (std::size_t i = 0; i < FrameMailbox::kMaxLockstepBacklog; ++i) ASSERT_EQ(Send(Step()), Outcome::kNoReply);
  EXPECT_EQ(Drain().size(), FrameMailbox::kMaxLockstepBacklog);
  ExpectError(Send(Step()), proto::ERROR_CODE_INVALID_STATE, false, {"already waiting"});
}

// ---- Controls ------------------------------------------------------------

// Entities come and go (Configure), so only the sim thread can tell whether
// an id is a car: the command carries the link it answers an Error through
// (tests/integration/bad_input_test.cpp checks that answer).
TEST_F(ClientProtocolTest, ControlsForAnyEntityGoToTheSimThreadWithTheLink) {
  Handshake();
  EXPECT_EQ(Send(Controls(100, 0, 0, 0)), Outcome::kNoReply);
  const std::vector<Command> posted = Drain();
  ASSERT_EQ(posted.size(), 1u);
  const auto& controls = std::get<ControlsCommand>(posted[0].body);
  EXPECT_EQ(controls.entity_id, 100u);
  EXPECT_EQ(controls.link, link_);
}

// Controls and TrackerOutput need no answer, so nothing else holds a flood
// back while the sim thread is busy: the queue refuses them past its bound.
TEST_F(ClientProtocolTest, ControlsAndTrackerOutputsPastTheQueueBoundAreDroppedWithAnError) {
  Handshake();
  for (std::size_t i = 0; i < limits::kMaxQueuedCommands; ++i) {
    ASSERT_EQ(Send(Controls(1, 0, 0.5f, 0)), Outcome::kNoReply) << i;
  }
  const auto expect_dropped = [&](Outcome outcome, const std::string& what) {
    EXPECT_EQ(outcome, Outcome::kReply);
    EXPECT_EQ(reply_.error().code(), proto::ERROR_CODE_INVALID_STATE);
    EXPECT_FALSE(reply_.error().fatal());
    for (const std::string& part : {"this " + what + " was dropped", std::string("16384 commands already wait"),
                                    std::string("limits::kMaxQueuedCommands")}) {
      EXPECT_NE(reply_.error().message().find(part), std::string::npos) << reply_.error().message();
    }
  };
  expect_dropped(Send(Controls(1, 0, 0.5f, 0)), "Controls");
  expect_dropped(Send(Tracker(1, 0, 0, 10, 10, 1)), "TrackerOutput");
  EXPECT_EQ(Drain().size(), limits::kMaxQueuedCommands) << "the refused ones were posted";
  EXPECT_EQ(Send(Controls(1, 0, 0.5f, 0)), Outcome::kNoReply) << "the sim thread drained: room again";
}

TEST_F(ClientProtocolTest, ControlsOutOfRangeNameTheField) {
  Handshake();
  struct Case {
    float steering, throttle, brake;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases = {
      {kNaN, 0, 0, {"Controls.steering is nan", "[-1, 1]"}},
      {kInf, 0, 0, {"Controls.steering is inf"}},
      {-kInf, 0, 0, {"Controls.steering is -inf"}},
      {1.5f, 0, 0, {"Controls.steering is 1.5", "[-1, 1]"}},
      {-1.01f, 0, 0, {"Controls.steering"}},
      {0, kNaN, 0, {"Controls.throttle is nan", "[0, 1]"}},
      {0, kInf, 0, {"Controls.throttle is inf"}},
      {0, -0.1f, 0, {"Controls.throttle", "[0, 1]"}},
      {0, 1.01f, 0, {"Controls.throttle"}},
      {0, 0, kNaN, {"Controls.brake is nan"}},
      {0, 0, kInf, {"Controls.brake is inf"}},
      {0, 0, 2, {"Controls.brake is 2", "[0, 1]"}},
      {0, 0, -1, {"Controls.brake is -1"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.parts[0]);
    ExpectError(Send(Controls(sim::kCarEntityId, c.steering, c.throttle, c.brake)), proto::ERROR_CODE_INVALID_ARGUMENT,
                false, c.parts);
  }
}

TEST_F(ClientProtocolTest, ControlsPostAControlsCommand) {
  Handshake();
  EXPECT_EQ(Send(Controls(sim::kCarEntityId, -0.25f, 0.5f, 0.75f)), Outcome::kNoReply);
  // The bounds are inclusive.
  EXPECT_EQ(Send(Controls(sim::kCarEntityId, 1, 1, 1)), Outcome::kNoReply);
  EXPECT_EQ(Send(Controls(sim::kCarEntityId, -1, 0, 0)), Outcome::kNoReply);
  const auto commands = Drain();
  ASSERT_EQ(commands.size(), 3u);
  EXPECT_EQ(commands[0].client, kClient);
  const auto& controls = std::get<ControlsCommand>(commands[0].body);
  EXPECT_EQ(controls.entity_id, sim::kCarEntityId);
  EXPECT_FLOAT_EQ(controls.steering, -0.25f);
  EXPECT_FLOAT_EQ(controls.throttle, 0.5f);
  EXPECT_FLOAT_EQ(controls.brake, 0.75f);
  EXPECT_FLOAT_EQ(std::get<ControlsCommand>(commands[2].body).steering, -1.0f);
}

TEST_F(ClientProtocolTest, ControlsNeedNoSubscription) {
  Handshake();
  EXPECT_FALSE(protocol_.subscribed());
  EXPECT_EQ(Send(Controls(sim::kCarEntityId, 0, 0, 1)), Outcome::kNoReply);
  EXPECT_EQ(Drain().size(), 1u);
}

// ---- TrackerOutput -------------------------------------------------------

TEST_F(ClientProtocolTest, TrackerOutputOutOfRangeNamesTheField) {
  Handshake();
  ExpectError(Send(Tracker(1, kNaN, 0, 10, 10, 0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.box.x is nan", "finite"});
  ExpectError(Send(Tracker(1, 0, kInf, 10, 10, 0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.box.y is inf"});
  ExpectError(Send(Tracker(1, 0, 0, 0, 10, 0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.box.width is 0"});
  ExpectError(Send(Tracker(1, 0, 0, 10, -2, 0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.box.height is -2"});
  ExpectError(Send(Tracker(1, 0, 0, 10, kNaN, 0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.box.height is nan"});
  ExpectError(Send(Tracker(1, 0, 0, 10, 10, 1.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.confidence is 1.5", "[0, 1]"});
  ExpectError(Send(Tracker(1, 0, 0, 10, 10, -0.5f)), proto::ERROR_CODE_INVALID_ARGUMENT, false,
              {"TrackerOutput.confidence is -0.5"});
  // A TrackerOutput without a box has width 0.
  proto::Envelope no_box;
  no_box.mutable_tracker_output()->set_frame_id(3);
  ExpectError(Send(no_box), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"TrackerOutput.box.width"});
}

TEST_F(ClientProtocolTest, TrackerOutputPostsACommand) {
  Handshake();
  // Negative positions are fine (a box partly off the left edge).
  EXPECT_EQ(Send(Tracker(42, -3.5f, 20.25f, 30, 40.5f, 0.9f)), Outcome::kNoReply);
  EXPECT_EQ(Send(Tracker(43, 0, 0, 1, 1, 0)), Outcome::kNoReply);  // confidence 0 allowed
  const auto commands = Drain();
  ASSERT_EQ(commands.size(), 2u);
  EXPECT_EQ(commands[0].client, kClient);
  const auto& t = std::get<TrackerOutputCommand>(commands[0].body);
  EXPECT_EQ(t.frame_id, 42u);
  EXPECT_FLOAT_EQ(t.x, -3.5f);
  EXPECT_FLOAT_EQ(t.y, 20.25f);
  EXPECT_FLOAT_EQ(t.width, 30.0f);
  EXPECT_FLOAT_EQ(t.height, 40.5f);
  EXPECT_FLOAT_EQ(t.confidence, 0.9f);
}

// ---- GetState ------------------------------------------------------------

TEST_F(ClientProtocolTest, GetStateBeforeTheFirstFrameIsEmpty) {
  Handshake();
  ASSERT_EQ(Send(GetState()), Outcome::kReply);
  ASSERT_TRUE(reply_.has_state());
  EXPECT_EQ(reply_.state().frame_id(), 0u);
  EXPECT_EQ(reply_.state().entities_size(), 0);
  EXPECT_FALSE(reply_.state().has_last_tracker_output());
  EXPECT_TRUE(Drain().empty());
}

TEST_F(ClientProtocolTest, GetStateReturnsTheSnapshotWithOnlyThisClientsTrackerOutput) {
  Handshake();
  StateSnapshot* snapshot = nullptr;
  StateRef ref = state_pool_.Acquire(&snapshot);
  snapshot->state.set_frame_id(12);
  snapshot->state.set_sim_time(0.4);
  proto::EntityState* car = snapshot->state.add_entities();
  car->set_id(sim::kCarEntityId);
  car->set_name("car");
  car->mutable_position()->set_x(3.5);
  snapshot->state.add_entities()->set_id(sim::kUavEntityId);
  for (ClientId client : {3u, kClient, 9u}) {
    proto::TrackerOutput output;
    output.set_frame_id(client * 10);
    output.mutable_box()->set_x(static_cast<float>(client));
    output.set_confidence(0.5f);
    snapshot->tracker_clients.push_back(client);
    snapshot->tracker_outputs.push_back(output);
  }
  latest_state_.Publish(std::move(ref));

  ASSERT_EQ(Send(GetState()), Outcome::kReply);
  ASSERT_TRUE(reply_.has_state());
  const proto::State& state = reply_.state();
  EXPECT_EQ(state.frame_id(), 12u);
  EXPECT_DOUBLE_EQ(state.sim_time(), 0.4);
  ASSERT_EQ(state.entities_size(), 2);
  EXPECT_EQ(state.entities(0).name(), "car");
  EXPECT_DOUBLE_EQ(state.entities(0).position().x(), 3.5);
  EXPECT_EQ(state.entities(1).id(), sim::kUavEntityId);
  ASSERT_TRUE(state.has_last_tracker_output());
  EXPECT_EQ(state.last_tracker_output().frame_id(), kClient * 10);
  EXPECT_FLOAT_EQ(state.last_tracker_output().box().x(), static_cast<float>(kClient));
  // The published snapshot itself is untouched.
  EXPECT_FALSE(latest_state_.Get()->state.has_last_tracker_output());
}

TEST_F(ClientProtocolTest, GetStateWithoutThisClientsTrackerOutputHasNone) {
  Handshake();
  StateSnapshot* snapshot = nullptr;
  StateRef ref = state_pool_.Acquire(&snapshot);
  snapshot->state.set_frame_id(5);
  proto::TrackerOutput other;
  other.set_frame_id(4);
  snapshot->tracker_clients.push_back(kClient + 1);
  snapshot->tracker_outputs.push_back(other);
  latest_state_.Publish(std::move(ref));
  ASSERT_EQ(Send(GetState()), Outcome::kReply);
  EXPECT_EQ(reply_.state().frame_id(), 5u);
  EXPECT_FALSE(reply_.state().has_last_tracker_output());
}

// ---- GetStats ------------------------------------------------------------

TEST_F(ClientProtocolTest, GetStatsBeforeHelloIsFatal) {
  proto::Envelope get_stats;
  get_stats.mutable_get_stats();
  ExpectError(Send(get_stats), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {"got field 13"});
}

TEST_F(ClientProtocolTest, GetStatsReportsTheCounters) {
  Handshake();
  proto::Envelope get_stats;
  get_stats.mutable_get_stats();
  ASSERT_EQ(Send(get_stats), Outcome::kReply);
  ASSERT_TRUE(reply_.has_stats());
  EXPECT_TRUE(reply_.stats().counters().empty());
  counters_.Add("udp.datagrams_truncated", 3);
  counters_.Add("shm.replies_dropped");
  ASSERT_EQ(Send(get_stats), Outcome::kReply);
  ASSERT_TRUE(reply_.has_stats());
  const auto& counters = reply_.stats().counters();
  EXPECT_EQ(counters.size(), 2u);
  ASSERT_TRUE(counters.contains("udp.datagrams_truncated"));
  EXPECT_EQ(counters.at("udp.datagrams_truncated"), 3u);
  ASSERT_TRUE(counters.contains("shm.replies_dropped"));
  EXPECT_EQ(counters.at("shm.replies_dropped"), 1u);
  EXPECT_TRUE(Drain().empty());
}

// ---- Bounded names and outstanding Configures ------------------------------

TEST_F(ClientProtocolTest, OverlongClientNameIsRefusedFatallyWithASmallError) {
  ExpectError(Send(Hello(wire::kProtocolVersion, std::string(1 << 20, 'n'))), proto::ERROR_CODE_INVALID_ARGUMENT, true,
              {"Hello.client_name is 1048576 bytes long", "at most 64", "limits::kMaxNameBytes"});
  EXPECT_LT(reply_.ByteSizeLong(), 512u);
  EXPECT_EQ(protocol_.client_name(), "");
  ExpectError(Send(GetState()), proto::ERROR_CODE_NOT_HANDSHAKEN, true, {});
  // A name of exactly the limit is fine.
  ASSERT_EQ(Send(Hello(wire::kProtocolVersion, std::string(limits::kMaxNameBytes, 'n'))), Outcome::kReply);
  EXPECT_TRUE(reply_.has_welcome());
}

TEST_F(ClientProtocolTest, OverlongCameraNameIsRefusedWithASmallError) {
  Handshake();
  ExpectError(Send(Subscribe(std::string(10 << 20, 'c'), {proto::CHANNEL_RGB})), proto::ERROR_CODE_INVALID_ARGUMENT,
              false, {"Subscribe.camera 'ccc", "(10485760 bytes)", "limits::kMaxNameBytes"});
  EXPECT_LT(reply_.ByteSizeLong(), 512u);
  // An unknown camera's name is quoted with its control characters escaped.
  ExpectError(Send(Subscribe("a\nb", {proto::CHANNEL_RGB})), proto::ERROR_CODE_UNKNOWN_CAMERA, false,
              {"no camera named 'a\\x0ab'"});
}

TEST_F(ClientProtocolTest, MoreChannelsThanThereAreIsRefusedBeforeLooking) {
  Handshake();
  ExpectError(Send(Subscribe("uav", std::vector<int>(100000, proto::CHANNEL_RGB))), proto::ERROR_CODE_INVALID_ARGUMENT,
              false,
              {"Subscribe.channels has 100000 entries", "at most " + std::to_string(channels::kSubscribableCount)});
}

proto::Envelope GetWorldRequest(uint32_t request_id) {
  proto::Envelope e;
  e.mutable_configure()->set_request_id(request_id);
  e.mutable_configure()->mutable_get_world();
  return e;
}

TEST_F(ClientProtocolTest, ConfiguresOverTheOutstandingLimitAreRefusedUntilOneIsAnswered) {
  Handshake();
  const uint32_t limit = limits::kMaxOutstandingConfigures;
  for (uint32_t id = 1; id <= limit; ++id) ASSERT_EQ(Send(GetWorldRequest(id)), Outcome::kNoReply) << id;
  // Taken by the sim thread, not yet carried out: still outstanding.
  std::vector<Command> commands = Drain();
  ASSERT_EQ(commands.size(), limit);
  ExpectError(Send(GetWorldRequest(99)), proto::ERROR_CODE_INVALID_STATE, false,
              {"Configure 99", std::to_string(limit) + " Configure requests", "limits::kMaxOutstandingConfigures",
               "wait for the answers"});
  EXPECT_EQ(reply_.error().request_id(), 99u);

  // What the sim thread does: carry them out and answer through each request's link.
  auto& first = std::get<ConfigureCommand>(commands[0].body);
  proto::Envelope answer;
  answer.mutable_configured()->set_request_id(first.request.request_id());
  first.link->OfferReply(answer);
  ASSERT_EQ(link_->replies.size(), 1u) << "the answer reaches the client's own link";
  EXPECT_EQ(link_->replies[0].configured().request_id(), 1u);
  // Answered: the client may send one more at once, even before the command is destroyed.
  EXPECT_EQ(Send(GetWorldRequest(5)), Outcome::kNoReply);
  EXPECT_EQ(Send(GetWorldRequest(6)), Outcome::kReply);
  // Commands dropped unanswered (the daemon stopping) give their slots back too.
  commands.clear();
  for (uint32_t id = 10; id < 10 + limit - 1; ++id) EXPECT_EQ(Send(GetWorldRequest(id)), Outcome::kNoReply) << id;
  EXPECT_EQ(Send(GetWorldRequest(20)), Outcome::kReply);
}

TEST_F(ClientProtocolTest, ConfiguresRefusedForTheirFieldsTakeNoSlot) {
  Handshake();
  proto::Envelope bad;
  bad.mutable_configure()->set_request_id(1);
  for (int i = 0; i < 10; ++i) {
    ExpectError(Send(bad), proto::ERROR_CODE_INVALID_ARGUMENT, false, {"carries no request"});
  }
  for (uint32_t id = 1; id <= limits::kMaxOutstandingConfigures; ++id) {
    EXPECT_EQ(Send(GetWorldRequest(id)), Outcome::kNoReply) << id;
  }
}

// ---- Disconnect and Refuse -----------------------------------------------

TEST_F(ClientProtocolTest, DisconnectPostsOnce) {
  protocol_.Disconnect();
  protocol_.Disconnect();
  const auto commands = Drain();
  ASSERT_EQ(commands.size(), 1u);
  EXPECT_EQ(commands[0].client, kClient);
  EXPECT_TRUE(std::holds_alternative<DisconnectCommand>(commands[0].body));
}

TEST(ClientProtocolRefuseTest, RefuseFillsTheError) {
  proto::Envelope reply;
  EXPECT_EQ(ClientProtocol::Refuse(proto::ERROR_CODE_MESSAGE_TOO_LARGE, "too big", true, reply),
            Outcome::kReplyAndClose);
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_MESSAGE_TOO_LARGE);
  EXPECT_EQ(reply.error().message(), "too big");
  EXPECT_TRUE(reply.error().fatal());
  EXPECT_EQ(ClientProtocol::Refuse(proto::ERROR_CODE_MALFORMED_MESSAGE, "bad", false, reply), Outcome::kReply);
  EXPECT_FALSE(reply.error().fatal());
}

TEST(ClientIdTest, NewClientIdsAreDistinctAndIncreasing) {
  const ClientId a = NewClientId();
  const ClientId b = NewClientId();
  EXPECT_GE(a, 1u);
  EXPECT_GT(b, a);
}

}  // namespace
}  // namespace sim4cv::session
