// What a hostile or broken TCP client can make the daemon hold or wait for
// (issue 14, findings 4, 9, 11, 12 and 13), each sent exactly as found to the
// real daemon: memory stays bounded, other clients go on being served, and
// the offender gets a fatal Error naming the limit and its flag.
#include <sys/resource.h>
#include <sys/wait.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <thread>

#include "server/common/limits.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/integration/raw_connection.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
constexpr std::size_t kMiB = 1u << 20;

class HardeningTcpTest : public DaemonTest {
 protected:
  // A lockstep client that has seen a few frames: the daemon's pools are warm.
  std::unique_ptr<Client> HealthyClient() {
    auto client = Connect("healthy");
    client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    for (int i = 0; i < 5; ++i) client->StepAndReceive();
    return client;
  }

  std::unique_ptr<RawConnection> Handshaken(const std::string& name = "raw") {
    auto raw = std::make_unique<RawConnection>(daemon_->tcp_port());
    EXPECT_TRUE(raw->Send(FramedHello(name)));
    const auto welcome = raw->Receive();
    EXPECT_TRUE(welcome && welcome->has_welcome());
    return raw;
  }

  // Sends `request` pipelined, as fast as the daemon takes it and never
  // reading, for `duration`; the healthy client steps meanwhile. Returns the
  // daemon's largest RSS seen.
  std::size_t FloodWithoutReading(RawConnection& flood, const proto::Envelope& request, Client& healthy,
                                  std::chrono::milliseconds duration) {
    std::string block;
    const std::string one = Framed(request);
    while (block.size() < 64 * 1024) block += one;
    std::size_t peak = daemon_->rss_bytes(), offset = 0;
    const auto end = Clock::now() + duration;
    auto next_step = Clock::now();
    while (Clock::now() < end) {
      const long sent = flood.TrySend(block.data() + offset, block.size() - offset);
      if (sent < 0) break;  // closed by the daemon
      offset = (offset + static_cast<std::size_t>(sent)) % block.size();
      if (sent == 0 || Clock::now() >= next_step) {
        EXPECT_GE(healthy.StepAndReceive(5000ms).frame_id(), 1u) << "another client must still get frames";
        peak = std::max(peak, daemon_->rss_bytes());
        next_step = Clock::now() + 50ms;
      }
    }
    return peak;
  }

  // The flooding client was either held back (still open) or closed with a
  // fatal Error naming the limit on the sim thread's answers.
  static void ExpectHeldBackOrClosedNamingTheLimit(RawConnection& flood) {
    const auto error = flood.ErrorThenClose(1000ms);
    std::cout << (flood.closed() ? "the flooding client was closed" : "the flooding client was held back") << "\n";
    if (!flood.closed()) return;  // back-pressure: the daemon stopped reading it
    ASSERT_TRUE(error.has_value()) << "closed without an Error";
    EXPECT_TRUE(error->fatal());
    EXPECT_NE(error->message().find("kMaxOfferedReplyBytes"), std::string::npos) << error->message();
  }
};

// Finding 4: a length prefix announcing 64 MiB allocated 64 MiB before any
// byte of the body came; 8 such connections pinned 512 MiB.
TEST_F(HardeningTcpTest, LengthPrefixesAloneMakeTheDaemonHoldNothing) {
  StartDaemon({"--max-message-bytes", std::to_string(64 * kMiB)});
  auto healthy = HealthyClient();
  const std::size_t before = daemon_->rss_bytes();
  std::vector<std::unique_ptr<RawConnection>> senders;
  std::string prefix_and_some(wire::kLengthPrefixBytes + 1000, '\0');
  wire::EncodeLengthPrefix(64 * kMiB, reinterpret_cast<uint8_t*>(prefix_and_some.data()));
  for (int i = 0; i < 8; ++i) {
    senders.push_back(Handshaken());
    ASSERT_TRUE(senders.back()->Send(prefix_and_some));
  }
  for (int i = 0; i < 10; ++i) healthy->StepAndReceive();  // the TCP thread has read what came by now
  std::this_thread::sleep_for(200ms);
  EXPECT_LT(daemon_->rss_bytes(), before + 16 * kMiB) << "before: " << before;
}

// Finding 4: memory taken for one large message is given back once it is
// handled, while its client stays connected, and when it leaves.
TEST_F(HardeningTcpTest, ALargeMessagesMemoryIsGivenBackAfterItIsHandled) {
  StartDaemon({"--max-message-bytes", std::to_string(64 * kMiB)});
  auto healthy = HealthyClient();
  const std::size_t before = daemon_->rss_bytes();
  const auto returns_near_before = [&] {
    std::size_t now = 0;
    for (const auto deadline = Clock::now() + 5s; Clock::now() < deadline; std::this_thread::sleep_for(50ms)) {
      healthy->StepAndReceive();
      now = daemon_->rss_bytes();
      if (now < before + 16 * kMiB) break;
    }
    return now;
  };
  auto large = Connect("large");
  proto::Envelope request;
  request.mutable_get_state();
  request.GetReflection()->MutableUnknownFields(&request)->AddLengthDelimited(1000, std::string(60 * kMiB, 'x'));
  large->SendEnvelope(request);  // legal: an unknown field is ignored
  EXPECT_EQ(large->GetState().entities_size(), 2);
  EXPECT_LT(returns_near_before(), before + 16 * kMiB) << "before: " << before << "; the client is still connected";
  large->Close();
  EXPECT_LT(returns_near_before(), before + 16 * kMiB) << "before: " << before << "; the client left";
}

// Finding 9: a 10-byte Configure{GetWorld} is answered with the whole
// WorldInfo; pipelined without reading, the answers grew the daemon by 150 MB/s.
TEST_F(HardeningTcpTest, PipelinedGetWorldWithoutReadingStaysBounded) {
  StartDaemon();
  auto healthy = HealthyClient();
  const std::size_t before = daemon_->rss_bytes();
  auto flood = Handshaken("flood");
  proto::Envelope request;
  request.mutable_configure()->set_request_id(7);
  request.mutable_configure()->mutable_get_world();
  const std::size_t peak = FloodWithoutReading(*flood, request, *healthy, 4000ms);
  std::cout << "RSS " << before / kMiB << " MiB before, at most " << peak / kMiB << " MiB during the flood\n";
  EXPECT_LT(peak, before + 24 * kMiB) << "before: " << before;
  ExpectHeldBackOrClosedNamingTheLimit(*flood);
}

// Finding 9: 13-byte Controls for an entity that is not a car, each answered
// with an Error by the sim thread, grew it by 23 MB/s.
TEST_F(HardeningTcpTest, PipelinedControlsRefusedBySimThreadWithoutReadingStayBounded) {
  StartDaemon();
  auto healthy = HealthyClient();
  const std::size_t before = daemon_->rss_bytes();
  auto flood = Handshaken("flood");
  proto::Envelope request;
  request.mutable_controls()->set_entity_id(2);  // the UAV
  request.mutable_controls()->set_throttle(0.5f);
  const std::size_t peak = FloodWithoutReading(*flood, request, *healthy, 4000ms);
  std::cout << "RSS " << before / kMiB << " MiB before, at most " << peak / kMiB << " MiB during the flood\n";
  EXPECT_LT(peak, before + 24 * kMiB) << "before: " << before;
  ExpectHeldBackOrClosedNamingTheLimit(*flood);
}

// Finding 11: messages of the largest size the daemon accepts, sent in a
// loop by 4 clients, must not stall another client's Step -> Frame.
TEST_F(HardeningTcpTest, MaxSizeMessagesDoNotStallOtherClients) {
  const char* override_bytes = std::getenv("SIM4CV_TEST_MAX_MESSAGE_BYTES");  // to measure other sizes
  const std::size_t max_bytes = override_bytes ? std::stoul(override_bytes) : limits::kDefaultMaxMessageBytes;
  StartDaemon({"--max-message-bytes", std::to_string(max_bytes)});
  // A SetRoute for an entity that does not exist, as many waypoints as fit.
  proto::Envelope request;
  request.mutable_configure()->set_request_id(1);
  auto* route = request.mutable_configure()->mutable_set_route();
  route->set_entity_id(999);
  route->set_speed(5);
  auto* points = route->mutable_waypoints()->mutable_points();
  const int count = static_cast<int>((max_bytes - 64) / 20);  // 20 bytes a point, 64 for the rest
  points->Reserve(count);
  for (int i = 0; i < count; ++i) {
    auto* point = points->Add();
    point->set_x(1.5 + i);
    point->set_y(2.5);
  }
  ASSERT_LE(request.ByteSizeLong(), max_bytes);
  const std::string bytes = Framed(request);
  std::atomic<bool> stop{false};
  std::atomic<int> sent{0};
  std::vector<std::thread> senders;
  for (int i = 0; i < 4; ++i) {
    senders.emplace_back([&, i] {
      Client client;
      client.Connect("127.0.0.1", daemon_->tcp_port(), "large-" + std::to_string(i));
      proto::Envelope answer;
      while (!stop) {
        client.SendRaw(bytes.data(), bytes.size());
        if (!client.ReceiveEnvelope(answer, 30000ms)) break;
        ++sent;
      }
    });
  }
  auto victim = HealthyClient();
  std::vector<double> latencies_ms;
  for (const auto end = Clock::now() + 4s; Clock::now() < end;) {
    const auto start = Clock::now();
    victim->StepAndReceive(30000ms);
    latencies_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  stop = true;
  for (auto& t : senders) t.join();

  std::sort(latencies_ms.begin(), latencies_ms.end());
  const double median = latencies_ms[latencies_ms.size() / 2];
  const double p95 = latencies_ms[latencies_ms.size() * 95 / 100];
  std::cout << "Step->Frame with 4 clients sending " << bytes.size() << "-byte messages (" << sent
            << " sent): median " << median << " ms, p95 " << p95 << " ms, max " << latencies_ms.back() << " ms, "
            << latencies_ms.size() << " frames\n";
  RecordProperty("median_ms", std::to_string(median));
  EXPECT_GT(sent, 4) << "the large messages must have been sent";
  // Before the fix (64 MiB messages by default) the worst wait was seconds;
  // a 2 MiB message costs the TCP thread milliseconds. Generous for a loaded machine.
  EXPECT_LT(latencies_ms.back(), 2000.0) << "median " << median << " ms, p95 " << p95 << " ms";
}

}  // namespace
}  // namespace sim4cv::testing
