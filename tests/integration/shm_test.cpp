// The shared-memory transport against the real daemon: the listening line and
// Welcome, a tracker loop over shared memory alone in lockstep mode (frames
// through the ring, Hello/Subscribe/Step/TrackerOutput/Controls/GetState
// through the reply ring), and frames byte-identical to the same frame over TCP,
// also from a ring that carries RGB alone (--shm-channels rgb).
#include <algorithm>
#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "protocol/shm_sync.h"
#include "tests/integration/shm_fixture.h"
#include "tests/support/frame_ages.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

TEST_F(ShmDaemonTest, ListeningLineAndWelcomeNameTheObject) {
  StartShmDaemon();
  EXPECT_EQ(ListeningField(daemon_->listening_line(), "shm"), shm_name_) << daemon_->listening_line();
  auto tcp = Connect();
  bool listed = false;
  for (const auto& t : tcp->welcome().transports()) {
    listed = listed || (t.kind() == proto::TRANSPORT_KIND_SHM && t.address() == shm_name_);
  }
  EXPECT_TRUE(listed) << tcp->welcome().DebugString();
  auto shm = OpenShm();
  EXPECT_EQ(shm->camera(), "uav");
  EXPECT_EQ(shm->header().camera_width, 320u);
  EXPECT_EQ(shm->header().camera_height, 180u);
  EXPECT_EQ(shm->header().writer_pid, static_cast<uint32_t>(daemon_->pid()));
  EXPECT_EQ(shm->header().expiry_ms, 5000u);
}

TEST_F(ShmDaemonTest, LockstepTrackerLoopOverSharedMemoryAlone) {
  StartShmDaemon();
  auto shm = OpenShm();
  const proto::Welcome welcome = shm->Hello("shm-tracker");
  EXPECT_EQ(welcome.mode(), proto::SIM_MODE_LOCKSTEP);
  EXPECT_GT(welcome.client_id(), 0u);
  // RGB alone, no BOXES: every slot carries the boxes anyway (the ring subscribes to them).
  shm->Subscribe(proto::DELIVERY_LOCKSTEP, {proto::CHANNEL_RGB});
  EXPECT_FALSE(shm->WaitForFrame(0, 300ms)) << "a lockstep daemon must not advance before the first Step";

  uint64_t last = 0;
  for (uint64_t expected = 1; expected <= 5; ++expected) {
    shm->Step();
    ASSERT_TRUE(shm->WaitForFrame(last, 10000ms)) << "no frame after Step " << expected;
    FrameView view;
    ASSERT_TRUE(shm->AcquireNewest(view));
    EXPECT_EQ(view.frame_id(), expected);
    EXPECT_NEAR(view.sim_time(), static_cast<double>(expected) / 30.0, 1e-9);
    ASSERT_TRUE(view.image(proto::CHANNEL_RGB).has_value());
    const auto car =
        std::find_if(view.boxes().begin(), view.boxes().end(), [](const ShmBox& b) { return b.object_id == 1; });
    ASSERT_NE(car, view.boxes().end()) << "the UAV camera sees the car";
    EXPECT_FALSE(view.stale());
    last = view.frame_id();
    shm->SendTrackerOutput(last, static_cast<float>(car->x), static_cast<float>(car->y), static_cast<float>(car->width),
                           static_cast<float>(car->height), 0.9f);
  }
  // Frames advance only when this client Steps.
  EXPECT_FALSE(shm->WaitForFrame(last, 500ms));
  EXPECT_EQ(shm->newest_frame_id(), 5u);

  // The tracker output of frame 5 is taken in before frame 6.
  shm->Step();
  ASSERT_TRUE(shm->WaitForFrame(5, 10000ms));
  const proto::State state = shm->GetState();
  EXPECT_EQ(state.frame_id(), 6u);
  EXPECT_EQ(state.last_tracker_output().frame_id(), 5u);
  EXPECT_FLOAT_EQ(state.last_tracker_output().confidence(), 0.9f);
  EXPECT_EQ(shm->responses_lost(), 0u);
}

TEST_F(ShmDaemonTest, ControlsOverSharedMemoryStopTheCar) {
  StartShmDaemon();
  auto shm = OpenShm();
  shm->Hello("shm-driver");
  shm->Subscribe(proto::DELIVERY_LOCKSTEP);
  uint64_t last = 0;
  OwnedFrame frame;
  auto step = [&](int frames) {
    for (int i = 0; i < frames; ++i) {
      shm->Step();
      ASSERT_TRUE(shm->WaitForFrame(last, 10000ms));
      ASSERT_TRUE(shm->ReadNewest(frame));
      last = frame.frame_id;
    }
  };
  step(60);  // 2 s: the lane follower drives the car up to speed
  ASSERT_EQ(frame.entities.size(), 2u);
  EXPECT_EQ(frame.entities[0].id, 1u);
  EXPECT_GT(Speed(frame.entities[0]), 2.0) << "the car should be driving";
  shm->SendControls(1, 0.0f, 0.0f, 1.0f);  // full brake
  step(40);
  EXPECT_LT(Speed(frame.entities[0]), 0.2) << "full brake for 1.3 s stops the car";
  // A TCP client sees the same state.
  auto tcp = Connect("observer");
  const proto::State state = tcp->GetState();
  EXPECT_EQ(state.frame_id(), last);
  EXPECT_NEAR(state.entities(0).position().x(), frame.entities[0].position[0], 1e-9);
  EXPECT_NEAR(state.entities(0).position().y(), frame.entities[0].position[1], 1e-9);
}

// Boxes and poses of the ring's copy of a frame equal the TCP Frame's.
void ExpectSameBoxesAndPoses(const OwnedFrame& owned, const proto::Frame& frame) {
  ASSERT_EQ(owned.boxes.size(), static_cast<std::size_t>(frame.boxes_size()));
  EXPECT_EQ(owned.box_total, owned.boxes.size());
  for (int b = 0; b < frame.boxes_size(); ++b) {
    const proto::Box& want = frame.boxes(b);
    const ShmBox& got = owned.boxes[static_cast<std::size_t>(b)];
    EXPECT_EQ(got.object_id, want.object_id());
    EXPECT_EQ(got.object_class, static_cast<uint32_t>(want.object_class()));
    EXPECT_EQ(got.x, want.x());
    EXPECT_EQ(got.y, want.y());
    EXPECT_EQ(got.width, want.width());
    EXPECT_EQ(got.height, want.height());
    EXPECT_EQ(got.visibility, want.visibility());
    EXPECT_EQ(got.visible_pixels, want.visible_pixels());
  }
  ASSERT_EQ(owned.entities.size(), static_cast<std::size_t>(frame.state().entities_size()));
  for (int e = 0; e < frame.state().entities_size(); ++e) {
    const proto::EntityState& want = frame.state().entities(e);
    const ShmEntityPose& got = owned.entities[static_cast<std::size_t>(e)];
    EXPECT_EQ(got.id, want.id());
    EXPECT_EQ(got.position[0], want.position().x());
    EXPECT_EQ(got.orientation[0], want.orientation().w());
    EXPECT_EQ(got.linear_velocity[1], want.linear_velocity().y());
  }
}

// The ring's copy of `channel` holds the very bytes TCP sent.
void ExpectSamePlane(const OwnedFrame& owned, const proto::Frame& frame, proto::Channel channel) {
  const auto sent = FindImage(frame, channel);
  const auto copied = owned.image(channel);
  ASSERT_TRUE(sent && copied) << proto::Channel_Name(channel);
  ASSERT_EQ(copied->stride, sent->stride) << proto::Channel_Name(channel);
  EXPECT_EQ(copied->element, sent->element);
  EXPECT_EQ(copied->components, sent->components);
  EXPECT_EQ(std::memcmp(copied->data, sent->data, std::size_t{sent->stride} * frame.height()), 0)
      << proto::Channel_Name(channel) << " differs";
}

// Steps a TCP lockstep client (`subscribed` channels) `frames` times; for each
// frame, `check` gets the ring's copy of the same frame id and the TCP Frame.
template <typename Check>
void CompareWithTcp(Client& tcp, ShmClient& shm, int frames, Check check,
                    const std::vector<proto::Channel>& subscribed = kAllChannels) {
  tcp.Subscribe("uav", subscribed, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  OwnedFrame owned;
  for (int i = 0; i < frames; ++i) {
    const proto::Frame& frame = tcp.StepAndReceive();
    // The ring has this frame, and no newer one: the sim waits for our Step.
    ASSERT_TRUE(shm.WaitForFrame(frame.frame_id() - 1, 5000ms));
    ASSERT_TRUE(shm.ReadNewest(owned));
    ASSERT_EQ(owned.frame_id, frame.frame_id());
    EXPECT_EQ(owned.sim_time, frame.sim_time());
    EXPECT_EQ(owned.render_end_mono_ns, frame.render_end_mono_ns());
    ASSERT_EQ(owned.width, frame.width());
    ASSERT_EQ(owned.height, frame.height());
    ExpectSamePlane(owned, frame, proto::CHANNEL_RGB);
    ExpectSameBoxesAndPoses(owned, frame);
    check(owned, frame);
  }
}

TEST_F(ShmDaemonTest, FramesAreByteIdenticalToTcpFrames) {
  StartShmDaemon();
  auto tcp = Connect("tcp-lockstep");
  auto shm = OpenShm();
  CompareWithTcp(*tcp, *shm, 4, [](const OwnedFrame& owned, const proto::Frame& frame) {
    ExpectSamePlane(owned, frame, proto::CHANNEL_DEPTH);
    ExpectSamePlane(owned, frame, proto::CHANNEL_MASK);
  });
}

// A ring carrying every channel of protocol/channels.h: each reaches a shm
// client byte for byte as TCP sends it.
TEST_F(ShmDaemonTest, EveryChannelIsByteIdenticalToTcp) {
  StartShmDaemon({"--shm-channels", channels::Names(channels::kAllPixels)});
  auto tcp = Connect("tcp-lockstep");
  auto shm = OpenShm();
  EXPECT_EQ(shm->header().channel_mask, channels::kAllPixels);
  CompareWithTcp(*tcp, *shm, 3, [](const OwnedFrame& owned, const proto::Frame& frame) {
    for (const channels::ChannelInfo& info : channels::kPixelChannels) ExpectSamePlane(owned, frame, info.id);
  });
}

// --shm-channels rgb: the same RGB bytes as TCP sends, depth and mask absent
// (not garbage), smaller slots, and a Subscribe asking for depth is refused.
TEST_F(ShmDaemonTest, RgbOnlyRingCarriesTcpsRgbAndNothingElse) {
  StartShmDaemon({"--shm-channels", "rgb"});
  auto shm = OpenShm();
  EXPECT_EQ(shm->header().channel_mask, 1u << proto::CHANNEL_RGB);
  EXPECT_EQ(shm->header().slot_bytes, shm::AlignUp(shm::kShmFrameHeaderBytes + 320 * 180 * 3, 4096));
  EXPECT_TRUE(shm->carries(proto::CHANNEL_RGB));
  EXPECT_FALSE(shm->carries(proto::CHANNEL_DEPTH) || shm->carries(proto::CHANNEL_MASK));
  auto tcp = Connect("tcp-lockstep");
  CompareWithTcp(*tcp, *shm, 4, [](const OwnedFrame& owned, const proto::Frame&) {
    EXPECT_FALSE(owned.has(proto::CHANNEL_DEPTH));
    EXPECT_FALSE(owned.has(proto::CHANNEL_MASK));
    EXPECT_FALSE(owned.image(proto::CHANNEL_DEPTH) || owned.image(proto::CHANNEL_MASK));
  });
  FrameView view;
  ASSERT_TRUE(shm->AcquireNewest(view));
  EXPECT_TRUE(view.has(proto::CHANNEL_RGB));
  EXPECT_FALSE(view.image(proto::CHANNEL_DEPTH).has_value());
  EXPECT_FALSE(view.image(proto::CHANNEL_MASK).has_value());

  shm->Hello("rgb-only");
  try {
    shm->Subscribe(proto::DELIVERY_NEWEST, {proto::CHANNEL_RGB, proto::CHANNEL_DEPTH});
    ADD_FAILURE() << "a Subscribe for DEPTH from an RGB-only ring was accepted";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_INVALID_ARGUMENT);
    for (const char* part : {"CHANNEL_DEPTH", "--shm-channels", "carries only rgb"}) {
      EXPECT_NE(std::string(error.what()).find(part), std::string::npos) << error.what();
    }
  }
  shm->Subscribe(proto::DELIVERY_NEWEST);  // asks for what the ring carries: accepted
}

TEST_F(ShmDaemonTest, ReplyRoundTripIsFast) {
  StartShmDaemon();
  auto shm = OpenShm();
  shm->Hello("latency");
  std::vector<double> micros;
  for (int i = 0; i < 300; ++i) {
    const auto start = std::chrono::steady_clock::now();
    shm->GetState();
    micros.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(micros.begin(), micros.end());
  const double median = micros[micros.size() / 2];
  std::printf("shm GetState round trip: median %.1f us, p90 %.1f us, max %.1f us\n", median,
              micros[micros.size() * 9 / 10], micros.back());
  // The target is < 100 us on an idle host; the bound leaves room for a loaded CI machine.
  EXPECT_LT(median, 5000.0);
}

}  // namespace
}  // namespace sim4cv::testing

namespace sim4cv::testing {
namespace {

// Over shared memory the newest slot is always the newest frame: a 10 Hz
// reader of a 30 Hz stream copies frames at most a frame period (plus the
// copy) old (docs/protocol.md 7.3).
TEST_F(ShmDaemonTest, TheNewestSlotIsAtMostAFramePeriodOld) {
  StartShmDaemon({"--mode", "realtime", "--frame-hz", "30"});
  auto shm = OpenShm();
  ASSERT_TRUE(shm->WaitForFrame(0, std::chrono::milliseconds(10000)));
  FrameAges ages;
  OwnedFrame frame;
  for (int i = 0; i < 20; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_TRUE(shm->ReadNewest(frame));
    ages.Add(frame.render_end_mono_ns);
  }
  ages.Print("shm frame age at 10 Hz of 30 Hz, newest slot");
  EXPECT_LT(ages.Percentile(0.5), 33.0 + 20.0);
  EXPECT_LT(ages.Percentile(0.9), 33.0 + 60.0);
}

}  // namespace
}  // namespace sim4cv::testing
