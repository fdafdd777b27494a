// Connections that hold a slot without finishing anything, and running out
// of file descriptors (found by a hostile-user probe), against the real
// daemon: timeouts close such connections with a fatal Error naming the
// timeout's flag, the accept loop waits instead of spinning, and
// --max-clients is checked against the descriptor limit at start.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "server/common/limits.h"
#include "tests/integration/daemon_fixture.h"
#include "tests/integration/raw_connection.h"
#include "tests/integration/run_to_exit.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

class HardeningTcpTimeoutsTest : public DaemonTest {
 protected:
  std::unique_ptr<RawConnection> Raw() { return std::make_unique<RawConnection>(daemon_->tcp_port()); }

  std::unique_ptr<RawConnection> Handshaken() {
    auto raw = Raw();
    EXPECT_TRUE(raw->Send(FramedHello("raw", daemon_->access_token())));
    const auto welcome = raw->Receive();
    EXPECT_TRUE(welcome && welcome->has_welcome());
    return raw;
  }

  // Sends `bytes` one at a time, `gap` apart, until the daemon answers or closes.
  static std::optional<proto::Error> Trickle(RawConnection& raw, const std::string& bytes,
                                             std::chrono::milliseconds gap) {
    for (char byte : bytes) {
      if (!raw.Send(std::string(1, byte))) break;
      if (const auto answer = raw.Receive(gap); answer && answer->has_error()) return answer->error();
      if (raw.closed()) break;
    }
    return std::nullopt;
  }

  // The daemon sends `raw` a fatal Error with `code` naming `flag` (unless
  // `error` already holds it), then closes it.
  static void ExpectClosedNaming(RawConnection& raw, proto::ErrorCode code, const std::string& flag,
                                 std::optional<proto::Error> error = std::nullopt) {
    if (!error) error = raw.ErrorThenClose(10000ms);
    raw.ErrorThenClose(10000ms);  // then EOF
    ASSERT_TRUE(error.has_value()) << "no Error within 10 s";
    EXPECT_EQ(error->code(), code) << error->message();
    EXPECT_TRUE(error->fatal());
    EXPECT_NE(error->message().find(flag), std::string::npos) << error->message();
    EXPECT_TRUE(raw.closed()) << "the connection must close after the Error";
  }

  void ExpectServes() {
    auto client = Connect("after");
    client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    EXPECT_GE(client->StepAndReceive().frame_id(), 1u);
  }
};

// docs/reliability.md, finding 13: silent connections held every --max-clients slot for ever.
TEST_F(HardeningTcpTimeoutsTest, SilentConnectionsAreClosedAfterTheHandshakeTimeout) {
  StartDaemon({"--max-clients", "4", "--handshake-timeout-ms", "500"});
  std::vector<std::unique_ptr<RawConnection>> silent;
  for (int i = 0; i < 4; ++i) silent.push_back(Raw());
  for (auto& raw : silent) ExpectClosedNaming(*raw, proto::ERROR_CODE_NOT_HANDSHAKEN, "--handshake-timeout-ms");
  ExpectServes();
}

// docs/reliability.md, finding 13: a Hello sent one byte at a time never completes in time.
TEST_F(HardeningTcpTimeoutsTest, AHelloTrickledByteByByteIsClosedAfterTheHandshakeTimeout) {
  StartDaemon({"--handshake-timeout-ms", "500", "--message-timeout-ms", "0"});
  auto raw = Raw();
  const auto error = Trickle(*raw, FramedHello("a-long-name-sent-slowly", daemon_->access_token()), 100ms);
  ExpectClosedNaming(*raw, proto::ERROR_CODE_NOT_HANDSHAKEN, "--handshake-timeout-ms", error);
}

// docs/reliability.md, finding 13: once a message has started, it must end within --message-timeout-ms.
TEST_F(HardeningTcpTimeoutsTest, AMessageTrickledByteByByteIsClosedAfterTheMessageTimeout) {
  StartDaemon({"--message-timeout-ms", "500"});
  auto raw = Handshaken();
  proto::Envelope state;
  state.mutable_tracker_output()->set_frame_id(1);
  state.mutable_tracker_output()->set_confidence(0.5f);
  const auto error = Trickle(*raw, Framed(state), 200ms);
  ExpectClosedNaming(*raw, proto::ERROR_CODE_INVALID_STATE, "--message-timeout-ms", error);
  ExpectServes();
}

// A handshaken client that is silent (a lockstep client paused in a
// debugger) stays by default; --idle-timeout-ms closes it when set.
TEST_F(HardeningTcpTimeoutsTest, IdleClientsStayByDefault) {
  StartDaemon({"--handshake-timeout-ms", "300", "--message-timeout-ms", "300"});
  auto client = Connect("paused");
  client->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  std::this_thread::sleep_for(1500ms);
  EXPECT_GE(client->StepAndReceive().frame_id(), 1u);
}

TEST_F(HardeningTcpTimeoutsTest, IdleTimeoutClosesSilentClientsButNotReaders) {
  StartDaemon({"--mode", "realtime", "--frame-hz", "20", "--idle-timeout-ms", "700"});
  auto reader = Connect("reader");  // only reads frames: not idle
  reader->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_NEWEST);
  auto silent = Handshaken();
  proto::Frame frame;
  for (const auto end = Clock::now() + 1500ms; Clock::now() < end;) ASSERT_TRUE(reader->ReceiveFrame(frame, 5000ms));
  ExpectClosedNaming(*silent, proto::ERROR_CODE_INVALID_STATE, "--idle-timeout-ms");
  EXPECT_GE(reader->GetState().entities_size(), 2);
}

// A fatal Error behind a write the client never reads: the connection
// closes after kCloseLingerMs all the same (its descriptor goes).
TEST_F(HardeningTcpTimeoutsTest, AFatalErrorTheClientDoesNotReadStillClosesTheConnection) {
  StartDaemon({"--mode", "realtime", "--width", "640", "--height", "480"});
  auto stuck = Handshaken();
  proto::Envelope subscribe;
  subscribe.mutable_subscribe()->set_camera("uav");
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_RGB);
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_DEPTH);
  subscribe.mutable_subscribe()->set_delivery(proto::DELIVERY_NEWEST);
  ASSERT_TRUE(stuck->Send(Framed(subscribe)));
  std::this_thread::sleep_for(1000ms);  // frames fill both sockets' buffers: the daemon's write waits
  const int fds = daemon_->open_fds();
  std::string oversized(wire::kLengthPrefixBytes, '\0');
  wire::EncodeLengthPrefix(limits::kDefaultMaxMessageBytes + 1, reinterpret_cast<uint8_t*>(oversized.data()));
  ASSERT_TRUE(stuck->Send(oversized));
  bool closed = false;
  for (const auto deadline = Clock::now() + 10s; !closed && Clock::now() < deadline;) {
    std::this_thread::sleep_for(100ms);
    closed = daemon_->open_fds() < fds;
  }
  EXPECT_TRUE(closed) << "the daemon still holds the connection of a client that does not read";
}

// docs/reliability.md, finding 12: out of descriptors, accept() failed at once, again and again:
// 100% CPU and 10 MB/s of warnings.
TEST_F(HardeningTcpTimeoutsTest, OutOfDescriptorsTheAcceptLoopWaitsInsteadOfSpinning) {
  StartDaemon();
  auto healthy = Connect("healthy");
  rlimit original{};
  ASSERT_EQ(prlimit(daemon_->pid(), RLIMIT_NOFILE, nullptr, &original), 0);
  rlimit low = original;
  low.rlim_cur = static_cast<rlim_t>(daemon_->open_fds() + 2);
  ASSERT_EQ(prlimit(daemon_->pid(), RLIMIT_NOFILE, &low, nullptr), 0);
  std::vector<std::unique_ptr<RawConnection>> waiting;
  for (int i = 0; i < 8; ++i) waiting.push_back(Raw());  // the kernel queues what the daemon cannot accept
  std::this_thread::sleep_for(300ms);
  const double cpu_before = CpuSeconds(daemon_->pid());
  const std::size_t log_before = daemon_->stderr_text().size();
  std::this_thread::sleep_for(2000ms);
  const double cpu = CpuSeconds(daemon_->pid()) - cpu_before;
  const std::size_t logged = daemon_->stderr_text().size() - log_before;
  EXPECT_LT(cpu, 0.5) << "CPU seconds in 2 s out of descriptors";
  EXPECT_LT(logged, 2000u) << daemon_->stderr_text().substr(log_before, 2000);
  EXPECT_GE(healthy->GetState().entities_size(), 2) << "connected clients are still served";
  waiting.clear();  // their descriptors go back once the daemon sees them close
  ExpectServes();
}

// docs/reliability.md, finding 12: --max-clients 100000 was accepted whatever the descriptor limit.
TEST(DescriptorLimitTest, MaxClientsBeyondTheHardLimitRefusesTheStart) {
  const auto [status, text] = RunToExit({"--max-clients", "1000", "--tcp-port", "0"}, rlimit{200, 200});
  EXPECT_EQ(status, 2) << text;
  for (const char* part : {"--max-clients 1000", "1064", "200", "ulimit -n"}) {
    EXPECT_NE(text.find(part), std::string::npos) << part << " in: " << text;
  }
}

TEST(DescriptorLimitTest, MaxClientsAboveTheSoftLimitRaisesIt) {
  rlimit mine{};
  getrlimit(RLIMIT_NOFILE, &mine);
  if (mine.rlim_max != RLIM_INFINITY && mine.rlim_max < 1064) GTEST_SKIP() << "hard limit " << mine.rlim_max;
  // The child's soft limit is 200: the daemon raises it to 1000 + 64 and serves.
  const rlimit low{200, mine.rlim_max};
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &low), 0);
  std::unique_ptr<DaemonProcess> daemon;
  EXPECT_NO_THROW(daemon = std::make_unique<DaemonProcess>(std::vector<std::string>{"--max-clients", "1000"}));
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &mine), 0);
  ASSERT_TRUE(daemon);
  rlimit raised{};
  ASSERT_EQ(prlimit(daemon->pid(), RLIMIT_NOFILE, nullptr, &raised), 0);
  EXPECT_GE(raised.rlim_cur, 1064u);
  Client client;
  client.Connect("127.0.0.1", daemon->tcp_port(), "after-raise");
  EXPECT_EQ(client.GetState().entities_size(), 2);
  client.Close();
  EXPECT_EQ(daemon->Stop(), 0);
}

}  // namespace
}  // namespace sim4cv::testing
