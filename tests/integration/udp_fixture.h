// Helpers shared by the UDP integration tests: the daemon's UDP port, UDP
// clients through the real client library, and counters from GetStats.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "sim4cv/udp_client.h"
#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {

class UdpDaemonTest : public DaemonTest {
 protected:
  uint16_t UdpPort() const {
    const std::string field = ListeningField(daemon_->listening_line(), "udp");
    EXPECT_FALSE(field.empty()) << "no udp= in: " << daemon_->listening_line();
    return static_cast<uint16_t>(std::stoi(field));
  }

  std::unique_ptr<UdpClient> ConnectUdp(const std::string& name = "udp-test") {
    auto client = std::make_unique<UdpClient>();
    client->Connect("127.0.0.1", UdpPort(), name);
    return client;
  }

  // A socket that never says Hello; no keep-alives either.
  std::unique_ptr<UdpClient> RawUdp() {
    auto client = std::make_unique<UdpClient>();
    client->Open("127.0.0.1", UdpPort());
    client->set_keepalive_interval(std::chrono::hours(1));
    return client;
  }

  static uint64_t Counter(const proto::Stats& stats, const std::string& name) {
    const auto found = stats.counters().find(name);
    return found == stats.counters().end() ? 0 : found->second;
  }

  // The daemon's counters, asked over TCP.
  proto::Stats TcpStats() {
    auto client = Connect("stats");
    proto::Envelope request;
    request.mutable_get_stats();
    client->SendEnvelope(request);
    proto::Envelope reply;
    EXPECT_TRUE(client->ReceiveEnvelope(reply, std::chrono::milliseconds(5000)));
    EXPECT_TRUE(reply.has_stats()) << reply.ShortDebugString();
    return reply.stats();
  }

  // Polls the counters over TCP until `name` reaches `at_least` (the UDP
  // thread adds its counts once per loop turn). Returns the last value.
  uint64_t WaitForCounter(const std::string& name, uint64_t at_least,
                          std::chrono::milliseconds timeout = std::chrono::milliseconds(5000)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    uint64_t value = 0;
    while ((value = Counter(TcpStats(), name)) < at_least && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return value;
  }
};

}  // namespace sim4cv::testing
