// Responses too long for a shared-memory response message (1984 bytes) reach
// the client whole, over its attachment socket: a Welcome naming many
// long-named entities, and States listing them, for every client that
// attaches, through ShmClient and through the Client facade that the
// Octave/MATLAB client uses. A client that falls behind loses only what the
// ring overwrote, and one that leaves its socket full gets an Error naming
// why instead of a stalled daemon.
#include <set>
#include <thread>

#include "tests/integration/shm_fixture.h"

namespace sim4cv::testing {
namespace {

constexpr int kEntities = 60;

class ShmLongResponsesTest : public ShmDaemonTest {
 protected:
  // Spawns kEntities UAVs with 63-byte names over TCP and steps once; returns the names.
  std::set<std::string> SpawnLongNamedEntities() {
    auto tcp = Connect("spawner");
    std::set<std::string> names;
    for (int i = 0; i < kEntities; ++i) {
      std::string name = "uav-with-a-name-as-long-as-the-daemon-allows-number-" + std::to_string(100 + i);
      name.resize(63, 'x');
      tcp->Spawn(proto::ENTITY_KIND_UAV, name, -100.0 + 6.0 * (i % 30), 60.0 + 6.0 * (i / 30), 25.0);
      names.insert(name);
    }
    // One frame, so the published State lists them too (each with its name).
    tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    tcp->StepAndReceive();
    auto fresh = Connect("size-check");
    EXPECT_GT(fresh->welcome().ByteSizeLong(), 2u * shm::kShmResponseDataBytes)
        << "the Welcome must be longer than a response message for this test to mean anything";
    return names;
  }

  static proto::Envelope HelloEnvelope(const std::string& name) {
    proto::Envelope envelope;
    envelope.mutable_hello()->set_protocol_version(1);
    envelope.mutable_hello()->set_client_name(name);
    return envelope;
  }

  // Waits until the daemon has written `count` responses into `shm`'s ring.
  static void WaitForResponses(ShmClient& shm, uint64_t count) {
    auto& written = shm::AreaMap(shm.area()).header().responses_written;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (shm::Atomic(written).load(std::memory_order_acquire) < count) {
      ASSERT_LT(std::chrono::steady_clock::now(), give_up) << "the daemon wrote only "
                                                           << shm::Atomic(written).load() << " responses";
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

  static void ExpectAllNamed(const google::protobuf::RepeatedPtrField<proto::EntityInfo>& entities,
                             const std::set<std::string>& names, const std::string& what) {
    std::set<std::string> got;
    for (const auto& entity : entities) got.insert(entity.name());
    for (const auto& name : names) EXPECT_TRUE(got.count(name)) << what << " lacks entity " << name;
  }
};

TEST_F(ShmLongResponsesTest, EveryAttachmentGetsAWelcomeNamingEveryEntity) {
  StartShmDaemon();
  const std::set<std::string> names = SpawnLongNamedEntities();
  for (int attempt = 1; attempt <= 3; ++attempt) {  // every new attachment, not only the first
    auto shm = OpenShm();
    const proto::Welcome welcome = shm->Hello("attach-" + std::to_string(attempt));
    ExpectAllNamed(welcome.entities(), names, "Welcome " + std::to_string(attempt));
    EXPECT_EQ(shm->responses_lost(), 0u);
    const proto::State state = shm->GetState();  // as long: every entity with its name
    EXPECT_GE(state.entities_size(), kEntities);
    EXPECT_GT(state.ByteSizeLong(), shm::kShmResponseDataBytes);
  }
  Client facade;  // the Octave/MATLAB client's path
  facade.Connect("shm://" + shm_name_, "facade");
  ExpectAllNamed(facade.welcome().entities(), names, "the Client facade's Welcome");
  EXPECT_EQ(Counter(*Connect("stats"), "shm.responses_too_large"), 0u);
}

TEST_F(ShmLongResponsesTest, AClientThatFallsALapBehindGetsTheLaterLongResponsesRight) {
  StartShmDaemon();
  SpawnLongNamedEntities();
  auto shm = OpenShm();
  shm->SendEnvelope(HelloEnvelope("lapped"));
  proto::Envelope get_state;
  get_state.mutable_get_state();
  for (std::size_t i = 0; i < shm::kShmResponseDepth; ++i) shm->SendEnvelope(get_state);
  WaitForResponses(*shm, shm::kShmResponseDepth + 1);
  // The Welcome was overwritten in the ring; its socket message is skipped,
  // and each State is the one its ring entry announced.
  int states = 0;
  proto::Envelope reply;
  while (shm->ReceiveReply(reply, std::chrono::milliseconds(100))) {
    ASSERT_TRUE(reply.has_state()) << reply.ShortDebugString().substr(0, 300);
    EXPECT_GE(reply.state().entities_size(), kEntities);
    ++states;
  }
  EXPECT_EQ(states, static_cast<int>(shm::kShmResponseDepth));
  EXPECT_EQ(shm->responses_lost(), 1u);
}

TEST_F(ShmLongResponsesTest, AClientThatLeavesItsSocketFullIsToldWhy) {
  StartShmDaemon();
  SpawnLongNamedEntities();
  auto shm = OpenShm();
  shm->Hello("hoarder");
  proto::Envelope get_state;
  get_state.mutable_get_state();
  constexpr int kRequests = 40;  // far more long replies than a socket queues
  for (int i = 0; i < kRequests; ++i) shm->SendEnvelope(get_state);
  WaitForResponses(*shm, 1 + kRequests);
  std::string refusal;
  proto::Envelope reply;
  while (shm->ReceiveReply(reply, std::chrono::milliseconds(100))) {
    if (reply.has_error()) refusal = reply.error().message();
  }
  EXPECT_NE(refusal.find("this client's socket still holds earlier long replies it has not read"), std::string::npos)
      << refusal;
  // The attachment goes on: once read, long replies fit again.
  EXPECT_GE(shm->GetState().entities_size(), kEntities);
}

}  // namespace
}  // namespace sim4cv::testing
