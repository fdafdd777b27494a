// Bad input over UDP: every datagram that cannot be used is dropped and
// counted (GetStats over TCP and UDP, and the daemon's log), nothing
// crashes, replies never multiply, and a registered client keeps getting
// frames throughout.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>
#include <utility>
#include <vector>

#include "tests/integration/udp_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

class UdpBadInputTest : public UdpDaemonTest {
 protected:
  void SetUp() override {
    // The healthy client says nothing while a flood runs (seconds on a busy
    // machine, the daemon stopped for some of them): its registration must
    // outlast that, which the default 5 s expiry did not.
    StartDaemon({"--udp-expiry-ms", "120000"});
    healthy_ = ConnectUdp("healthy");
    healthy_->Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  }

  // The registered client still gets frames.
  void ExpectHealthyClientServed(int frames = 3) {
    proto::Frame frame;
    for (int i = 0; i < frames; ++i) {
      healthy_->Step();
      ASSERT_TRUE(healthy_->ReceiveFrame(frame, 5000ms)) << "the registered client stopped getting frames";
      EXPECT_EQ(frame.images(0).data().size(), 320u * 180 * 3);
    }
  }

  static std::string Bytes(const proto::Envelope& envelope) { return envelope.SerializeAsString(); }

  static proto::Envelope ChunkEnvelope() {
    proto::Envelope envelope;
    proto::FrameChunk& chunk = *envelope.mutable_frame_chunk();
    chunk.set_frame_id(1);
    chunk.set_chunk_count(1);
    chunk.set_frame_bytes(4);
    chunk.set_data("abcd");
    return envelope;
  }

  static proto::Envelope StepEnvelope() {
    proto::Envelope envelope;
    envelope.mutable_step();
    return envelope;
  }

  // A plain UDP socket connected to the daemon.
  int ConnectedSocket() {
    const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    EXPECT_GE(fd, 0);
    sockaddr_in daemon{};
    daemon.sin_family = AF_INET;
    daemon.sin_port = htons(UdpPort());
    daemon.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(connect(fd, reinterpret_cast<const sockaddr*>(&daemon), sizeof daemon), 0);
    return fd;
  }

  // `count` Step datagrams with sendmmsg, 1000 per call: as fast as one core can send.
  static void Flood(int fd, int count) {
    std::string step = Bytes(StepEnvelope());
    std::vector<iovec> iov(1000, iovec{step.data(), step.size()});
    std::vector<mmsghdr> messages(1000);
    for (std::size_t i = 0; i < messages.size(); ++i) messages[i].msg_hdr = msghdr{nullptr, 0, &iov[i], 1, nullptr, 0, 0};
    for (int sent = 0; sent < count;) {
      const int n = sendmmsg(fd, messages.data(), static_cast<unsigned>(std::min<int>(1000, count - sent)), 0);
      if (n > 0) sent += n;
    }
  }

  // Polls GetStats over UDP until read + kernel-dropped datagrams reach `total`.
  std::pair<uint64_t, uint64_t> WaitForDrops(uint64_t total) {
    uint64_t read = 0, overflowed = 0;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (std::chrono::steady_clock::now() < deadline) {
      const proto::Stats stats = healthy_->GetStats();
      read = Counter(stats, "udp.unregistered_sender");
      overflowed = Counter(stats, "udp.receive_buffer_overflow");
      if (read + overflowed >= total) break;
      std::this_thread::sleep_for(50ms);
    }
    return {read, overflowed};
  }

  std::unique_ptr<UdpClient> healthy_;
};

TEST_F(UdpBadInputTest, EachBadDatagramIsDroppedAndCounted) {
  auto raw = RawUdp();
  // Truncated: a Subscribe whose datagram ends before its protobuf does.
  proto::Envelope subscribe;
  subscribe.mutable_subscribe()->set_camera("uav");
  const std::string whole = Bytes(subscribe);
  raw->SendRaw(whole.data(), whole.size() - 2);
  EXPECT_EQ(WaitForCounter("udp.malformed", 1), 1u);
  // Garbage.
  const std::string garbage = "\xff\xff\xff\xff\xff\x01 not protobuf";
  raw->SendRaw(garbage.data(), garbage.size());
  EXPECT_EQ(WaitForCounter("udp.malformed", 2), 2u);
  ExpectHealthyClientServed();
  // A FrameChunk, which only the daemon may send.
  raw->SendEnvelope(ChunkEnvelope());
  EXPECT_EQ(WaitForCounter("udp.client_frame_chunk", 1), 1u);
  // A valid request from an address that never said Hello: dropped, and told so.
  raw->SendEnvelope(StepEnvelope());
  EXPECT_EQ(WaitForCounter("udp.unregistered_sender", 1), 1u);
  proto::Envelope reply;
  ASSERT_TRUE(raw->ReceiveEnvelope(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.ShortDebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_NOT_HANDSHAKEN);
  EXPECT_FALSE(raw->ReceiveEnvelope(reply, 200ms)) << "garbage got an answer: " << reply.ShortDebugString();
  ExpectHealthyClientServed();

  // The registered client's own bad datagrams: an Error for garbage (not
  // fatal), silence for a chunk; it stays registered.
  healthy_->SendRaw(garbage.data(), garbage.size());
  ASSERT_TRUE(healthy_->ReceiveEnvelope(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.ShortDebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_MALFORMED_MESSAGE);
  EXPECT_FALSE(reply.error().fatal());
  EXPECT_NE(reply.error().message().find(std::to_string(garbage.size()) + "-byte"), std::string::npos)
      << reply.error().message();
  healthy_->SendEnvelope(ChunkEnvelope());
  ExpectHealthyClientServed();

  // The same counters over UDP, and in the log at shutdown.
  const proto::Stats stats = healthy_->GetStats();
  EXPECT_EQ(Counter(stats, "udp.malformed"), 3u);
  EXPECT_EQ(Counter(stats, "udp.client_frame_chunk"), 2u);
  EXPECT_EQ(Counter(stats, "udp.unregistered_sender"), 1u);
  EXPECT_EQ(daemon_->Stop(), 0);
  const std::string log = daemon_->stderr_text();
  EXPECT_NE(log.find("counter udp.malformed = 3"), std::string::npos) << log;
  EXPECT_NE(log.find("counter udp.unregistered_sender = 1"), std::string::npos) << log;
  daemon_.reset();
}

TEST_F(UdpBadInputTest, BurstOf100000DatagramsIsCountedWithoutAFloodOfReplies) {
  constexpr int kBurst = 100000;
  const int fd = ConnectedSocket();
  const auto start = std::chrono::steady_clock::now();
  std::thread flood([&] { Flood(fd, kBurst); });
  ExpectHealthyClientServed(20);  // while the flood is on
  flood.join();
  ExpectHealthyClientServed(5);
  // Each datagram was either read and dropped, or dropped by the kernel for
  // lack of buffer (SO_RXQ_OVFL, reported with the next datagram read).
  const auto [read, overflowed] = WaitForDrops(kBurst);
  EXPECT_GE(read + overflowed, 99u * kBurst / 100) << read << " read, " << overflowed << " overflowed";
  EXPECT_LE(read + overflowed, static_cast<uint64_t>(kBurst));
  // Replies to the unregistered address are rate-limited: a burst of 50, then 50 per second.
  std::this_thread::sleep_for(100ms);  // replies still on their way
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  int replies = 0;
  char buffer[2048];
  while (recv(fd, buffer, sizeof buffer, MSG_DONTWAIT) > 0) ++replies;
  close(fd);
  EXPECT_GE(replies, 1);
  EXPECT_LE(replies, 50 + static_cast<int>(50 * seconds) + 5) << "over " << seconds << " s";
  EXPECT_GE(Counter(healthy_->GetStats(), "udp.replies_rate_limited"), read - static_cast<uint64_t>(replies));
  EXPECT_TRUE(daemon_->running());
  std::printf("burst of %d: %llu read and dropped, %llu dropped by the kernel, %d replies in %.2f s\n", kBurst,
              static_cast<unsigned long long>(read), static_cast<unsigned long long>(overflowed), replies, seconds);
}

TEST_F(UdpBadInputTest, DatagramsTheKernelDropsAreCountedToo) {
  // A stopped daemon reads nothing: its socket buffer fills and the kernel drops the rest.
  constexpr int kBurst = 300000;
  const int fd = ConnectedSocket();
  ASSERT_EQ(kill(daemon_->pid(), SIGSTOP), 0);
  Flood(fd, kBurst);
  ASSERT_EQ(kill(daemon_->pid(), SIGCONT), 0);
  const auto [read, overflowed] = WaitForDrops(kBurst);
  close(fd);
  EXPECT_GT(overflowed, 0u) << "a " << kBurst << "-datagram burst fitted into the socket buffer";
  EXPECT_GT(read, 0u);
  // Plus, at most, a few of the healthy client's GetStats that met the still-full buffer.
  EXPECT_GE(read + overflowed, static_cast<uint64_t>(kBurst)) << read << " read, " << overflowed << " overflowed";
  EXPECT_LE(read + overflowed, static_cast<uint64_t>(kBurst) + 10) << read << " read, " << overflowed << " overflowed";
  ExpectHealthyClientServed();
  std::printf("stopped daemon, burst of %d: %llu read and dropped, %llu dropped by the kernel\n", kBurst,
              static_cast<unsigned long long>(read), static_cast<unsigned long long>(overflowed));
}

TEST_F(UdpBadInputTest, DuplicateAndLateSequencesAreIgnoredAndCounted) {
  proto::Envelope controls;
  controls.mutable_controls()->set_entity_id(1);
  controls.mutable_controls()->set_throttle(0.5f);
  const uint64_t sequence = healthy_->SendEnvelope(controls);
  healthy_->SendEnvelope(controls, sequence);      // the same datagram again
  healthy_->SendEnvelope(controls, sequence - 1);  // an older one, late
  EXPECT_EQ(WaitForCounter("udp.out_of_order", 2), 2u);

  // A duplicated Step must not buy a second frame.
  const uint64_t step_sequence = healthy_->SendEnvelope(StepEnvelope());
  healthy_->SendEnvelope(StepEnvelope(), step_sequence);
  proto::Frame frame;
  ASSERT_TRUE(healthy_->ReceiveFrame(frame, 5000ms));
  const uint64_t stepped = frame.frame_id();
  EXPECT_FALSE(healthy_->ReceiveFrame(frame, 300ms)) << "a duplicate Step produced frame " << frame.frame_id();
  EXPECT_EQ(Counter(healthy_->GetStats(), "udp.out_of_order"), 3u);
  // Sequence 0 means unsequenced: every one is applied.
  healthy_->SendEnvelope(StepEnvelope(), 0);
  healthy_->SendEnvelope(StepEnvelope(), 0);
  ASSERT_TRUE(healthy_->ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), stepped + 1);
  ASSERT_TRUE(healthy_->ReceiveFrame(frame, 5000ms));
  EXPECT_EQ(frame.frame_id(), stepped + 2);
}

TEST_F(UdpBadInputTest, RefusalsAreErrorsAndFatalOnesUnregister) {
  healthy_->SendControls(1, 3.0f, 0.0f, 0.0f);
  proto::Envelope reply;
  ASSERT_TRUE(healthy_->ReceiveEnvelope(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.ShortDebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_INVALID_ARGUMENT);
  EXPECT_FALSE(reply.error().fatal());
  EXPECT_NE(reply.error().message().find("Controls.steering is 3"), std::string::npos) << reply.error().message();
  ExpectHealthyClientServed(1);

  // Errors to one client are rate-limited too: a burst of 20, then 20 per second.
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 200; ++i) healthy_->SendControls(1, 3.0f, 0.0f, 0.0f);
  int errors = 0;
  while (healthy_->ReceiveEnvelope(reply, 200ms)) errors += reply.has_error() ? 1 : 0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(errors, 19);
  EXPECT_LE(errors, 21 + static_cast<int>(20 * seconds)) << "over " << seconds << " s";
  EXPECT_EQ(Counter(healthy_->GetStats(), "udp.replies_rate_limited"), 200u - static_cast<uint64_t>(errors));

  // A message only the server sends is fatal: the registration ends.
  proto::Envelope welcome;
  welcome.mutable_welcome()->set_scene_name("nope");
  healthy_->SendEnvelope(welcome);
  ASSERT_TRUE(healthy_->ReceiveEnvelope(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.ShortDebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_UNEXPECTED_MESSAGE);
  EXPECT_TRUE(reply.error().fatal());
  EXPECT_EQ(WaitForCounter("udp.closed_by_error", 1), 1u);
  healthy_->Step();
  ASSERT_TRUE(healthy_->ReceiveEnvelope(reply, 5000ms));
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_NOT_HANDSHAKEN) << reply.ShortDebugString();
}

}  // namespace
}  // namespace sim4cv::testing
