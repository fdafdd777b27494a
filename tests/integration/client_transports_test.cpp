// One sim4cv::Client, the same calls over TCP, UDP and shared memory
// (tcp://, udp://, shm:// addresses), against the real daemon; and what a
// user meets when something is wrong: a bad address, no daemon there, the
// daemon dying mid-session, another protocol version.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>

#include "sim4cv/shm_client.h"
#include "sim4cv/udp_client.h"
#include "tests/integration/shm_fixture.h"

namespace sim4cv::testing {
namespace {

using Ms = std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

enum class Transport { kTcp, kUdp, kShm };

std::string Name(Transport t) { return t == Transport::kTcp ? "tcp" : t == Transport::kUdp ? "udp" : "shm"; }

// A port nothing listens on (bound, read, closed again).
uint16_t UnusedPort(int type) {
  const int fd = socket(AF_INET, type, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address);
  socklen_t size = sizeof address;
  getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size);
  close(fd);
  return ntohs(address.sin_port);
}

class ClientTransportsTest : public ShmDaemonTest, public ::testing::WithParamInterface<Transport> {
 protected:
  void Start(std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--udp-port", "0", "--shm-channels", "rgb,depth,mask"});
    StartShmDaemon(std::move(args));
  }

  std::string Address() const {
    switch (GetParam()) {
      case Transport::kTcp:
        return "tcp://127.0.0.1:" + std::to_string(daemon_->tcp_port());
      case Transport::kUdp:
        return "udp://127.0.0.1:" + ListeningField(daemon_->listening_line(), "udp");
      case Transport::kShm:
        return "shm://" + shm_name_;
    }
    return "";
  }
};

TEST_P(ClientTransportsTest, TheSameCallsWorkOverEveryTransport) {
  Start({"--mode", "lockstep"});
  Client client;
  client.Connect(Address(), "transports-" + Name(GetParam()));
  EXPECT_EQ(client.address(), Address());
  EXPECT_EQ(client.udp() != nullptr, GetParam() == Transport::kUdp);
  EXPECT_EQ(client.shm() != nullptr, GetParam() == Transport::kShm);
  client.Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  uint64_t last = 0;
  for (int i = 0; i < 5; ++i) {
    const proto::Frame& frame = client.StepAndReceive();
    EXPECT_GT(frame.frame_id(), last);
    last = frame.frame_id();
    const auto rgb = FindImage(frame, proto::CHANNEL_RGB);
    ASSERT_TRUE(rgb);
    EXPECT_EQ(rgb->width, 320u);
    EXPECT_EQ(rgb->components, 3u);
    const auto depth = FindImage(frame, proto::CHANNEL_DEPTH);
    ASSERT_TRUE(depth);
    EXPECT_GT(*depth->at<float>(160, 170), 0.f);
    ASSERT_FALSE(frame.boxes().empty()) << "the UAV films the target car";
  }
  client.SendTrackerOutput(last, 10, 20, 30, 40, 0.5f);
  client.StepAndReceive();  // the State of the step after the output holds it
  EXPECT_EQ(client.GetState().last_tracker_output().frame_id(), last);
  const proto::Stats stats = client.GetStats();
  if (GetParam() == Transport::kUdp) {
    EXPECT_GT(stats.counters().at("udp.datagrams_received"), 0u);
  }

  // Configure on every transport (shm: through a TCP link of its own).
  const uint32_t uav = client.Spawn(proto::ENTITY_KIND_UAV, "uav_" + Name(GetParam()), 5, 5, 20);
  int named = 0;
  const proto::WorldInfo after_spawn = client.GetWorld();
  for (const auto& entity : after_spawn.entities()) named += entity.id() == uav;
  EXPECT_EQ(named, 1);
  const proto::WorldInfo world = client.UavVelocity(uav, 1, 0, 0);
  EXPECT_EQ(world.entities_size(), 3);
  client.Close();
  EXPECT_FALSE(client.connected());
  EXPECT_THROW(client.Step(), ConnectionError);
}

TEST_P(ClientTransportsTest, AnotherProtocolVersionIsRefusedWithTheReason) {
  Start();
  Client client;
  try {
    client.Connect(Address(), "old", Ms(5000), 99);
    FAIL() << "Hello with protocol version 99 was accepted";
  } catch (const ServerError& e) {
    EXPECT_EQ(e.code(), proto::ERROR_CODE_VERSION_MISMATCH);
    EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(client.connected());
}

TEST_P(ClientTransportsTest, TheDaemonStoppingMidSessionIsAnErrorNotAHang) {
  Start({"--mode", "lockstep"});
  Client client;
  client.Connect(Address());
  client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_LOCKSTEP);
  client.StepAndReceive();
  EXPECT_EQ(daemon_->Stop(), 0);
  daemon_.reset();
  const auto start = Clock::now();
  EXPECT_THROW(
      {
        client.Step();
        client.StepAndReceive(Ms(2000));
      },
      ConnectionError);
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(30));  // not hanging; margin for busy hosts
}

// A Configure retried over UDP (its answer lost, say) is carried out once:
// the daemon answers a request_id it has seen with the same answer.
TEST_F(DaemonTest, ARetriedConfigureOverUdpIsCarriedOutOnce) {
  StartDaemon({"--udp-port", "0"});
  Client client;
  client.Connect("udp://127.0.0.1:" + ListeningField(daemon_->listening_line(), "udp"));
  proto::Envelope spawn;
  spawn.mutable_configure()->set_request_id(7);
  auto& request = *spawn.mutable_configure()->mutable_spawn();
  request.set_kind(proto::ENTITY_KIND_UAV);
  request.set_name("once");
  request.mutable_position()->set_z(10);
  for (int i = 0; i < 3; ++i) client.SendEnvelope(spawn);  // retries while the first is pending get no answer
  std::vector<uint32_t> ids;
  proto::Envelope reply;
  const auto collect = [&](Ms quiet) {
    while (client.ReceiveEnvelope(reply, quiet)) {
      ASSERT_TRUE(reply.has_configured()) << reply.ShortDebugString();
      EXPECT_EQ(reply.configured().request_id(), 7u);
      ids.push_back(reply.configured().entity_id());
    }
  };
  collect(Ms(1000));
  ASSERT_GE(ids.size(), 1u);
  client.SendEnvelope(spawn);  // a retry after the answer: the same answer again
  collect(Ms(500));
  ASSERT_GE(ids.size(), 2u);
  for (const uint32_t id : ids) EXPECT_EQ(id, ids.front());
  const proto::WorldInfo world = client.GetWorld();
  int named = 0;
  for (const auto& entity : world.entities()) named += entity.name() == "once";
  EXPECT_EQ(named, 1);
  EXPECT_EQ(client.GetStats().counters().at("udp.configure_repeated"), 3u);
}

// The tracker loop docs/clients.md shows (clients/cpp/examples/tracker_loop.cpp)
// runs as written over every transport.
TEST_P(ClientTransportsTest, TheDocumentedTrackerLoopRuns) {
  Start({"--mode", "lockstep"});
  const std::string command = std::string(SIM4CV_TRACKER_LOOP) + " " + Address() + " 30 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string output;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, pipe)) output += buffer;
  EXPECT_EQ(pclose(pipe), 0) << output;
  EXPECT_EQ(output, "tracked 30 frames over " + Address() + "\n");
}

INSTANTIATE_TEST_SUITE_P(Transports, ClientTransportsTest,
                         ::testing::Values(Transport::kTcp, Transport::kUdp, Transport::kShm),
                         [](const auto& info) { return Name(info.param); });

TEST(ClientAddressTest, AnAddressOfAnotherFormNamesTheAcceptedOnes) {
  for (const std::string bad : {"127.0.0.1:5000", "http://x:1", "tcp://host", "udp://h:0", "tcp://h:99999", "shm://"}) {
    Client client;
    try {
      client.Connect(bad, "x", Ms(500));
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::invalid_argument& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("'" + bad + "'"), std::string::npos) << message;
      EXPECT_NE(message.find("tcp://HOST:PORT, udp://HOST:PORT or shm://NAME"), std::string::npos) << message;
    }
  }
}

TEST(ClientAddressTest, NoDaemonThereIsAClearErrorWithinTheTimeout) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"tcp://127.0.0.1:" + std::to_string(UnusedPort(SOCK_STREAM)), "refused"},
      {"udp://127.0.0.1:" + std::to_string(UnusedPort(SOCK_DGRAM)), "nothing listens"},
      {"shm:///sim4cv-nobody-" + std::to_string(getpid()), "no sim4cvd"}};
  for (const auto& [address, says] : cases) {
    Client client;
    const auto start = Clock::now();
    try {
      client.Connect(address, "x", Ms(1500));
      ADD_FAILURE() << address << " connected";
    } catch (const std::runtime_error& e) {
      const std::string message = e.what();
      const std::string where = address.substr(address.find("://") + 3);
      EXPECT_NE(message.find(where), std::string::npos) << message;
      EXPECT_NE(message.find(says), std::string::npos) << message;
    }
    EXPECT_LT(Clock::now() - start, Ms(30000)) << address;  // fails, not hangs; margin for busy hosts
  }
}

}  // namespace
}  // namespace sim4cv::testing
