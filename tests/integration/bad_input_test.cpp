// Every kind of bad input a client can send gets an Error naming the problem,
// closes at most that one connection, and leaves the daemon serving others.
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "protocol/framing.h"
#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

class BadInputTest : public DaemonTest {
 protected:
  void SetUp() override { StartDaemon(); }

  // Reads the next envelope; it must be an Error with `code`.
  static proto::Error ExpectError(Client& client, proto::ErrorCode code) {
    proto::Envelope envelope;
    EXPECT_TRUE(client.ReceiveEnvelope(envelope, 5000ms)) << "no reply within 5 s";
    EXPECT_TRUE(envelope.has_error()) << envelope.ShortDebugString();
    EXPECT_EQ(envelope.error().code(), code) << envelope.error().message();
    EXPECT_FALSE(envelope.error().message().empty());
    return envelope.error();
  }

  // After a fatal error the daemon closes the connection: the next read hits EOF.
  static void ExpectClosed(Client& client) {
    proto::Envelope envelope;
    EXPECT_THROW(client.ReceiveEnvelope(envelope, 5000ms), ConnectionError);
  }

  // A well-behaved client still gets frames from the daemon.
  void ExpectDaemonStillServes() {
    auto client = Connect("healthy");
    client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    EXPECT_GE(client->StepAndReceive().frame_id(), 1u);
  }

  static void SendWithPrefix(Client& client, uint32_t announced_size, const std::string& body) {
    uint8_t prefix[wire::kLengthPrefixBytes];
    wire::EncodeLengthPrefix(announced_size, prefix);
    client.SendRaw(prefix, sizeof prefix);
    if (!body.empty()) client.SendRaw(body.data(), body.size());
  }

  std::unique_ptr<Client> RawClient() {
    auto client = std::make_unique<Client>();
    client->ConnectRaw("127.0.0.1", daemon_->tcp_port());
    return client;
  }
};

TEST_F(BadInputTest, OversizedLengthPrefix) {
  auto client = Connect();
  SendWithPrefix(*client, wire::kDefaultMaxMessageBytes + 1, "");
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_MESSAGE_TOO_LARGE);
  EXPECT_TRUE(error.fatal());
  EXPECT_NE(error.message().find(std::to_string(wire::kDefaultMaxMessageBytes + 1)), std::string::npos) << error.message();
  EXPECT_NE(error.message().find("--max-message-bytes"), std::string::npos) << error.message();
  ExpectClosed(*client);
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, BytesThatAreNotAnEnvelope) {
  auto client = Connect();
  SendWithPrefix(*client, 6, std::string("\xff\xff\xff\xff\xff\xff", 6));
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_MALFORMED_MESSAGE);
  EXPECT_TRUE(error.fatal());
  EXPECT_NE(error.message().find("6 bytes"), std::string::npos) << error.message();
  ExpectClosed(*client);
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, EmptyEnvelope) {
  auto client = Connect();
  SendWithPrefix(*client, 0, "");
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_UNEXPECTED_MESSAGE);
  EXPECT_NE(error.message().find("no message"), std::string::npos) << error.message();
  ExpectClosed(*client);
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, UnknownOneofField) {
  auto client = Connect();
  // Field 99, varint 1: valid protobuf, but no message kind this server knows.
  SendWithPrefix(*client, 3, std::string("\x98\x06\x01", 3));
  ExpectError(*client, proto::ERROR_CODE_UNEXPECTED_MESSAGE);
  ExpectClosed(*client);
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, MessageOnlyTheServerSends) {
  auto client = Connect();
  proto::Envelope envelope;
  envelope.mutable_frame()->set_frame_id(3);
  client->SendEnvelope(envelope);
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_UNEXPECTED_MESSAGE);
  EXPECT_NE(error.message().find("only the server sends"), std::string::npos) << error.message();
  ExpectClosed(*client);
}

TEST_F(BadInputTest, RequestBeforeHandshake) {
  auto client = RawClient();
  proto::Envelope envelope;
  envelope.mutable_subscribe()->set_camera("uav");
  client->SendEnvelope(envelope);
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_NOT_HANDSHAKEN);
  EXPECT_TRUE(error.fatal());
  EXPECT_NE(error.message().find("Hello"), std::string::npos) << error.message();
  ExpectClosed(*client);
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, NanAndInfiniteNumbersAreRefusedButTheConnectionStays) {
  auto client = Connect();
  client->SendControls(1, std::numeric_limits<float>::quiet_NaN(), 0.5f, 0.f);
  proto::Error error = ExpectError(*client, proto::ERROR_CODE_INVALID_ARGUMENT);
  EXPECT_FALSE(error.fatal());
  EXPECT_NE(error.message().find("Controls.steering is nan"), std::string::npos) << error.message();

  client->SendTrackerOutput(1, std::numeric_limits<float>::infinity(), 0.f, 10.f, 10.f, 0.5f);
  error = ExpectError(*client, proto::ERROR_CODE_INVALID_ARGUMENT);
  EXPECT_NE(error.message().find("TrackerOutput.box.x is inf"), std::string::npos) << error.message();

  client->SendControls(1, 0.f, 1.5f, 0.f);
  error = ExpectError(*client, proto::ERROR_CODE_INVALID_ARGUMENT);
  EXPECT_NE(error.message().find("Controls.throttle is 1.5"), std::string::npos) << error.message();

  EXPECT_EQ(client->GetState().entities_size(), 2) << "the connection must stay usable";
}

TEST_F(BadInputTest, ControlsForAnEntityThatIsNotACar) {
  auto client = Connect();
  client->SendControls(2, 0.f, 0.5f, 0.f);
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_UNKNOWN_ENTITY);
  EXPECT_NE(error.message().find("entity_id 2"), std::string::npos) << error.message();
  EXPECT_EQ(client->GetState().entities_size(), 2);
}

TEST_F(BadInputTest, SubscriptionToACameraThatDoesNotExist) {
  auto client = Connect();
  try {
    client->Subscribe("front", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
    FAIL() << "subscribing to 'front' succeeded";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_UNKNOWN_CAMERA);
    EXPECT_FALSE(error.fatal());
    EXPECT_NE(std::string(error.what()).find("'front'"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("'uav'"), std::string::npos) << error.what();
  }
  client->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);  // same connection still works
  EXPECT_EQ(client->StepAndReceive().frame_id(), 1u);
}

TEST_F(BadInputTest, ClientVanishingInTheMiddleOfAMessage) {
  auto client = Connect();
  SendWithPrefix(*client, 1000, "only ten b");
  client->Close();
  ExpectDaemonStillServes();
}

TEST_F(BadInputTest, LockstepClientVanishingInTheMiddleOfAFrame) {
  auto steady = Connect("steady");
  auto leaver = Connect("leaver");
  steady->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  leaver->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  // Both step several times; the leaver never reads its ~500 KB frames and
  // disconnects while the daemon is writing them.
  for (int i = 0; i < 5; ++i) {
    steady->Step();
    leaver->Step();
  }
  proto::Frame frame;
  ASSERT_TRUE(steady->ReceiveFrame(frame, 5000ms));
  leaver->Close();
  for (uint64_t id = frame.frame_id() + 1; id <= 5; ++id) ASSERT_TRUE(steady->ReceiveFrame(frame, 5000ms));
  // From now on the simulation follows the steady client alone.
  for (int i = 0; i < 10; ++i) EXPECT_EQ(steady->StepAndReceive().frame_id(), 6u + i);
}

TEST_F(BadInputTest, StepWithoutLockstepSubscription) {
  auto client = Connect();
  client->Step();
  const proto::Error error = ExpectError(*client, proto::ERROR_CODE_INVALID_STATE);
  EXPECT_FALSE(error.fatal());
  EXPECT_NE(error.message().find("DELIVERY_LOCKSTEP"), std::string::npos) << error.message();
}

TEST_F(BadInputTest, TooManyClients) {
  daemon_->Stop();
  StartDaemon({"--max-clients", "1"});
  auto first = Connect("first");
  Client second;
  try {
    second.Connect("127.0.0.1", daemon_->tcp_port(), "second");
    FAIL() << "a second client was accepted with --max-clients 1";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_TOO_MANY_CLIENTS);
    EXPECT_NE(std::string(error.what()).find("--max-clients"), std::string::npos) << error.what();
  }
  EXPECT_EQ(first->GetState().entities_size(), 2);
}

}  // namespace
}  // namespace sim4cv::testing
