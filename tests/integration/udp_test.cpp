// The UDP transport against the real daemon: a whole tracker loop over UDP
// alone, compared byte for byte with the same frames over TCP; small
// datagrams; the version check; registration expiry; keep-alives.
#include <chrono>
#include <cmath>
#include <thread>

#include "tests/integration/udp_fixture.h"
#include "tests/support/frame_ages.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

TEST_F(UdpDaemonTest, TrackerLoopOverUdpMatchesTcpByteForByte) {
  StartDaemon();
  auto udp = ConnectUdp("udp-tracker");
  const proto::Welcome& welcome = udp->welcome();
  EXPECT_EQ(welcome.scene_name(), "default");
  EXPECT_GT(welcome.client_id(), 0u);
  bool lists_udp = false;
  for (const auto& t : welcome.transports()) {
    lists_udp = lists_udp || (t.kind() == proto::TRANSPORT_KIND_UDP && t.address() == std::to_string(UdpPort()));
  }
  EXPECT_TRUE(lists_udp) << welcome.ShortDebugString();

  auto tcp = Connect("tcp-reference");
  udp->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  tcp->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  proto::Frame over_udp, over_tcp;
  for (uint64_t expected_id = 1; expected_id <= 30; ++expected_id) {
    udp->Step();
    tcp->Step();
    ASSERT_TRUE(udp->ReceiveFrame(over_udp, 5000ms)) << "frame " << expected_id;
    ASSERT_TRUE(tcp->ReceiveFrame(over_tcp, 5000ms)) << "frame " << expected_id;
    ASSERT_EQ(over_udp.frame_id(), expected_id);
    ASSERT_EQ(over_tcp.frame_id(), expected_id);
    ASSERT_EQ(over_udp.images_size(), static_cast<int>(channels::kPixelChannelCount));  // every pixel channel
    EXPECT_EQ(over_udp.images(0).data().size(), 320u * 180 * 3);
    EXPECT_FALSE(over_udp.boxes().empty());
    EXPECT_EQ(over_udp.state().frame_id(), expected_id);
    // Pixels, boxes, state, times: the same bytes whichever transport carried them.
    EXPECT_EQ(over_udp.SerializeAsString(), over_tcp.SerializeAsString()) << "frame " << expected_id;
    const proto::Box& box = over_udp.boxes(0);
    udp->SendTrackerOutput(expected_id, static_cast<float>(box.x()), static_cast<float>(box.y()),
                           static_cast<float>(box.width()), static_cast<float>(box.height()), 0.9f);
  }
  // The simulation takes the last TrackerOutput in before the next frame.
  udp->Step();
  tcp->Step();
  ASSERT_TRUE(udp->ReceiveFrame(over_udp, 5000ms));
  ASSERT_TRUE(tcp->ReceiveFrame(over_tcp, 5000ms));
  const proto::State state = udp->GetState();
  EXPECT_EQ(state.frame_id(), 31u);
  EXPECT_EQ(state.last_tracker_output().frame_id(), 30u);
  EXPECT_FLOAT_EQ(state.last_tracker_output().confidence(), 0.9f);
  EXPECT_EQ(udp->frames_completed(), 31u);
  EXPECT_EQ(udp->frames_dropped_incomplete(), 0u);
  EXPECT_EQ(udp->chunks_ignored(), 0u);
  const proto::Stats stats = udp->GetStats();
  EXPECT_EQ(Counter(stats, "udp.frames_sent"), 31u);
  EXPECT_EQ(Counter(stats, "udp.registrations"), 1u);
}

TEST_F(UdpDaemonTest, MtuSizedDatagramsCarryWholeFrames) {
  StartDaemon({"--udp-datagram-bytes", "1472"});
  auto udp = ConnectUdp();
  udp->Subscribe("uav", kAllChannels, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  for (uint64_t expected_id = 1; expected_id <= 10; ++expected_id) {
    udp->Step();
    ASSERT_TRUE(udp->ReceiveFrame(frame, 5000ms));
    EXPECT_EQ(frame.frame_id(), expected_id);
    ASSERT_EQ(frame.images_size(), static_cast<int>(channels::kPixelChannelCount));
    for (int i = 0; i < frame.images_size(); ++i) {
      const channels::ChannelInfo* info = channels::Find(frame.images(i).channel());
      ASSERT_NE(info, nullptr);
      EXPECT_EQ(frame.images(i).data().size(), 320u * 180 * info->bytes_per_pixel) << info->name;
    }
  }
  const proto::Stats stats = udp->GetStats();
  // 1.7 MB of pixels in datagrams of at most 1472 bytes: over a thousand chunks per frame.
  EXPECT_EQ(Counter(stats, "udp.frames_sent"), 10u);
  EXPECT_GE(Counter(stats, "udp.chunks_sent"), 10u * 320 * 180 * 30 / 1472);
  EXPECT_EQ(udp->frames_dropped_incomplete(), 0u);
}

TEST_F(UdpDaemonTest, VersionMismatchIsRefusedOverUdp) {
  StartDaemon();
  UdpClient client;
  try {
    client.Connect("127.0.0.1", UdpPort(), "old", 5000ms, 7);
    FAIL() << "a version-7 Hello was accepted over UDP";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_VERSION_MISMATCH);
    EXPECT_TRUE(error.fatal());
    EXPECT_NE(std::string(error.what()).find("version 7"), std::string::npos) << error.what();
  }
  EXPECT_EQ(Counter(TcpStats(), "udp.registrations"), 0u);
  auto good = ConnectUdp();  // the daemon still serves
  EXPECT_EQ(good->welcome().scene_name(), "default");
}

TEST_F(UdpDaemonTest, SilentLockstepClientExpiresAndStopsBlockingOthers) {
  // The expiry leaves room for a busy machine to pause this test between
  // two of the UDP client's datagrams (300 ms once lapsed before its Subscribe).
  StartDaemon({"--udp-expiry-ms", "2000"});
  auto tcp = Connect("keeps-stepping");
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  auto udp = ConnectUdp("goes-silent");
  udp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  // Expiry counts from the UDP client's last datagram, its Step: timing from
  // before it sends gives a lower bound that a loaded machine cannot break.
  const auto start = std::chrono::steady_clock::now();
  udp->Step();
  tcp->Step();
  ASSERT_TRUE(udp->ReceiveFrame(frame, 5000ms));
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 5000ms));
  // The UDP client says nothing more; the simulation waits for it until its registration lapses.
  tcp->Step();
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 5000ms)) << "the expired UDP client still blocks lockstep";
  EXPECT_GE(std::chrono::steady_clock::now() - start, 1900ms);
  EXPECT_EQ(frame.frame_id(), 2u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(tcp->StepAndReceive(1000ms).frame_id(), 3u + i);
  EXPECT_EQ(Counter(TcpStats(), "udp.expired"), 1u);
  // The lapsed client is told so when it speaks again.
  udp->Step();
  proto::Envelope reply;
  ASSERT_TRUE(udp->ReceiveEnvelope(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.ShortDebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_NOT_HANDSHAKEN);
  EXPECT_NE(reply.error().message().find("lapsed"), std::string::npos) << reply.error().message();
}

TEST_F(UdpDaemonTest, KeepAlivesHoldANewestFrameRegistration) {
  // A client that only receives sends nothing but its keep-alives: it must
  // still be registered, and get frames, well past the expiry. The margins
  // hold on a busy machine (no frame count, which depends on its speed).
  StartDaemon({"--mode", "realtime", "--udp-expiry-ms", "1000"});
  auto udp = ConnectUdp("viewer");
  udp->set_keepalive_interval(100ms);
  udp->Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST);
  proto::Frame frame;
  uint64_t last_id = 0;
  const auto start = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - start < 2500ms) {
    ASSERT_TRUE(udp->ReceiveFrame(frame, 5000ms)) << "frames stopped after frame " << last_id;
    EXPECT_GT(frame.frame_id(), last_id);
    last_id = frame.frame_id();
  }
  EXPECT_EQ(Counter(udp->GetStats(), "udp.expired"), 0u);
}

TEST_F(UdpDaemonTest, ControlsOverUdpDriveTheCar) {
  StartDaemon();
  auto udp = ConnectUdp("driver");
  udp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  proto::Frame frame;
  auto run_frames = [&](int count) {
    for (int i = 0; i < count; ++i) {
      udp->Step();
      ASSERT_TRUE(udp->ReceiveFrame(frame, 5000ms));
    }
  };
  auto car_speed = [&] {
    const proto::State state = udp->GetState();
    EXPECT_GE(state.entities_size(), 1);
    const auto& v = state.entities(0).linear_velocity();
    return std::hypot(v.x(), v.y());
  };
  run_frames(30);  // 1 s on the built-in lane follower: the car picks up speed
  EXPECT_GT(car_speed(), 1.0);
  udp->SendControls(1, 0.0f, 0.0f, 1.0f);  // full brake, applied from the next step
  run_frames(45);
  EXPECT_LT(car_speed(), 0.1) << "the car ignored Controls sent over UDP";
}

}  // namespace
}  // namespace sim4cv::testing

namespace sim4cv::testing {
namespace {

// On-request delivery over UDP (docs/protocol.md 7.3): a 10 Hz reader of a
// 30 Hz stream gets frames at most a frame period plus their transfer old,
// and nothing it did not ask for.
TEST_F(UdpDaemonTest, OnRequestFramesAreAtMostAFramePeriodOld) {
  StartDaemon({"--mode", "realtime", "--frame-hz", "30"});
  auto client = ConnectUdp("udp-tracker");
  client->Subscribe("uav", {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH, proto::CHANNEL_MASK, proto::CHANNEL_BOXES},
                    proto::DELIVERY_ON_REQUEST);
  FrameAges ages;
  proto::Frame frame;
  uint64_t last = 0;
  for (int i = 0; i < 20; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_TRUE(client->RequestFrame(frame, std::chrono::milliseconds(5000)));
    ages.Add(frame.render_end_mono_ns());
    EXPECT_GT(frame.frame_id(), last);
    last = frame.frame_id();
  }
  proto::Frame extra;
  EXPECT_FALSE(client->ReceiveFrame(extra, std::chrono::milliseconds(300))) << "a frame nobody asked for";
  ages.Print("UDP frame age at 10 Hz of 30 Hz, on request");
  EXPECT_LT(ages.Percentile(0.5), 33.0 + 20.0);
  EXPECT_LT(ages.Percentile(0.9), 33.0 + 60.0);
}

}  // namespace
}  // namespace sim4cv::testing
