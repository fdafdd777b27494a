// What the reply-path tests of the transports share (tcp_reply_test,
// udp_reply_test, shm_reply_path_test): a ServerContext without a daemon, and
// a stand-in for the sim thread that finds each client's ClientLink in the
// command queue, as the real one does, and offers it replies and frames.
#pragma once

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "protocol/framing.h"
#include "server/session/server_context.h"
#include "server/sim/scene.h"
#include "server/transport/transport.h"

namespace sim4cv::test {

using namespace std::chrono_literals;

constexpr uint32_t kWidth = 32, kHeight = 24;

// A reply as the sim thread would send one, told apart by `marker` (a State
// stands in for any reply: the transports do not look inside).
inline proto::Envelope MarkedReply(uint64_t marker) {
  proto::Envelope reply;
  reply.mutable_state()->set_frame_id(marker);
  return reply;
}

inline proto::Envelope FatalError(const std::string& message) {
  proto::Envelope reply;
  reply.mutable_error()->set_code(proto::ERROR_CODE_INVALID_STATE);
  reply.mutable_error()->set_message(message);
  reply.mutable_error()->set_fatal(true);
  return reply;
}

// A client's subscription as the sim thread receives it.
struct Subscriber {
  session::ClientId client = 0;
  std::shared_ptr<session::ClientLink> link;
};

class SimStandIn {
 public:
  SimStandIn()
      : context_{scene_, proto::SIM_MODE_REALTIME, MakeWelcome(), world_, commands_, latest_state_, 1u << 20, counters_, "", ""} {
    world_.Publish(MakeWorld(scene_));
  }

  const session::ServerContext& context() const { return context_; }
  session::Counters& counters() { return counters_; }
  uint32_t camera_index() const { return static_cast<uint32_t>(scene_.FindCamera("uav")); }

  // The link of the next Subscribe posted (in posting order); fails the test
  // and returns an empty one if none comes.
  Subscriber WaitForSubscriber(std::chrono::milliseconds timeout = 5000ms) {
    Subscriber found;
    WaitFor(timeout, [&](const session::Command& command) {
      const auto* subscribe = std::get_if<session::SubscribeCommand>(&command.body);
      if (!subscribe || found.link) return false;
      found = {command.client, subscribe->link};
      return true;
    });
    EXPECT_TRUE(found.link) << "no Subscribe reached the sim thread";
    return found;
  }

  // True once the transport has told the sim thread that `client` is gone.
  bool WaitForDisconnect(session::ClientId client, std::chrono::milliseconds timeout = 5000ms) {
    return WaitFor(timeout, [&](const session::Command& command) {
      return command.client == client && std::holds_alternative<session::DisconnectCommand>(command.body);
    });
  }

  // A frame of camera "uav" (every pixel `id`), named `camera_name`.
  session::FrameRef MakeFrame(uint64_t id, const std::string& camera_name = "uav") {
    session::Frame* frame = nullptr;
    session::FrameRef ref = frames_.Acquire(&frame);
    frame->frame_id = id;
    frame->camera_index = camera_index();
    frame->camera_name = camera_name;
    frame->width = kWidth;
    frame->height = kHeight;
    std::ranges::fill(frame->Hold(proto::CHANNEL_RGB), static_cast<uint8_t>(id));
    std::ranges::fill(frame->Hold<float>(proto::CHANNEL_DEPTH), static_cast<float>(id));
    std::ranges::fill(frame->Hold<uint16_t>(proto::CHANNEL_MASK), static_cast<uint16_t>(id));
    return ref;
  }

 private:
  static proto::Welcome MakeWelcome() {
    proto::Welcome welcome;
    welcome.set_protocol_version(wire::kProtocolVersion);
    welcome.set_server_version("reply-path-test");
    welcome.set_mode(proto::SIM_MODE_REALTIME);
    welcome.set_physics_hz(240);
    welcome.set_frame_hz(30);
    return welcome;
  }

  static proto::WorldInfo MakeWorld(const sim::Scene& scene) {
    proto::WorldInfo world;
    world.set_scene_name(scene.name);
    for (const auto& spec : scene.cameras) {
      proto::CameraInfo* camera = world.add_cameras();
      camera->set_name(spec.name);
      camera->set_width(spec.width);
      camera->set_height(spec.height);
    }
    return world;
  }

  // Drains commands until `wanted` accepts one; the others are dropped.
  bool WaitFor(std::chrono::milliseconds timeout, const std::function<bool(const session::Command&)>& wanted) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    std::vector<session::Command> drained;
    for (;;) {
      commands_.Drain(drained);
      for (const session::Command& command : drained) {
        if (wanted(command)) return true;
      }
      if (std::chrono::steady_clock::now() >= deadline) return false;
      commands_.WaitUntil(std::min(deadline, std::chrono::steady_clock::now() + 10ms));
    }
  }

  session::FramePool frames_;  // first: outlives every frame a transport or a link holds
  const sim::Scene scene_ = sim::DefaultScene(kWidth, kHeight);
  session::WorldDirectory world_;
  session::CommandQueue commands_;
  session::StatePool states_;
  session::LatestState latest_state_;
  session::Counters counters_;
  session::ServerContext context_;
};

// The sim thread's stand-in: runs `body` on its own thread. The destructor
// asks it to stop (a failed assertion on the test's thread must not leave it
// waiting) and joins it.
class SimThreadStandIn {
 public:
  explicit SimThreadStandIn(std::function<void(const std::atomic<bool>& stop)> body)
      : thread_([this, body = std::move(body)] { body(stop_); }) {}
  ~SimThreadStandIn() {
    stop_ = true;
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Offers `rounds` times, on a stand-in sim thread, a reply marked i and then
// frame i to `link`, the way configuration replies and frames interleave.
// `frame_first`, if given, gets each frame just before `link` does (the shm
// ring's own link: the scheduler offers in client-id order, and the ring
// subscribed first). It stays at most `ahead` rounds ahead of
// `replies_seen`: no transport has to drop a reply for lack of room, and the
// transport's thread is busy sending while replies and frames come in, which
// is when a frame could overtake a reply (with a large lead it mostly sends
// replies, newest-frame delivery dropping the frames in between).
inline std::unique_ptr<SimThreadStandIn> OfferRepliesThenFrames(SimStandIn& sim, session::ClientLink& link,
                                                                uint64_t rounds, const std::atomic<uint64_t>& replies_seen,
                                                                session::ClientLink* frame_first = nullptr,
                                                                uint64_t ahead = 1) {
  return std::make_unique<SimThreadStandIn>([&sim, &link, rounds, &replies_seen, frame_first, ahead](
                                                const std::atomic<bool>& stop) {
    for (uint64_t i = 1; i <= rounds && !stop; ++i) {
      link.OfferReply(MarkedReply(i));
      const session::FrameRef frame = sim.MakeFrame(i);
      if (frame_first) frame_first->OfferFrame(frame);
      link.OfferFrame(frame);
      while (replies_seen + ahead < i && !stop) std::this_thread::sleep_for(50us);
    }
  });
}

// A socket transport on loopback, started on a stand-in sim thread's
// context, with one client subscribed (newest frames of "uav").
template <typename SocketClient>
class SocketReplyTest : public ::testing::Test {
 protected:
  virtual std::unique_ptr<transport::Transport> MakeTransport() = 0;

  void SetUp() override {
    transport_ = MakeTransport();
    transport_->Start(sim_.context());
    subscriber_ = Connect(client_);
  }
  void TearDown() override { transport_->Stop(); }

  // Connects (or registers) and subscribes `client`; its link as the sim thread gets it.
  Subscriber Connect(SocketClient& client) {
    client.Connect("127.0.0.1", static_cast<uint16_t>(std::stoi(transport_->info().address())), "reply-test");
    client.Subscribe("uav", {proto::CHANNEL_RGB}, proto::DELIVERY_NEWEST);
    return sim_.WaitForSubscriber();
  }

  // A frame reaches the client under the camera name it was rendered with.
  void ExpectFramesCarryTheirCameraName() {
    subscriber_.link->OfferFrame(sim_.MakeFrame(1, "uav-renamed"));
    proto::Frame frame;
    ASSERT_TRUE(client_.ReceiveFrame(frame, 5000ms));
    EXPECT_EQ(frame.camera(), "uav-renamed") << "the name comes from the frame, not from the scene";
  }

  // A reply, a fatal Error, then a reply and a frame: the first two arrive,
  // in order, and nothing after the fatal Error does; the sim thread hears
  // the client is gone. What the transport does next is its own test's.
  void ExpectFatalErrorEndsTheClient() {
    session::ClientLink& link = *subscriber_.link;
    link.OfferReply(MarkedReply(1));
    link.OfferReply(FatalError("the map could not be loaded"));
    link.OfferReply(MarkedReply(2));     // after the fatal Error: never sent
    link.OfferFrame(sim_.MakeFrame(1));  // nor is this
    proto::Envelope envelope;
    ASSERT_TRUE(client_.ReceiveEnvelope(envelope, 5000ms));
    EXPECT_EQ(envelope.state().frame_id(), 1u);
    ASSERT_TRUE(client_.ReceiveEnvelope(envelope, 5000ms));
    ASSERT_TRUE(envelope.has_error()) << envelope.DebugString();
    EXPECT_TRUE(envelope.error().fatal());
    EXPECT_EQ(envelope.error().message(), "the map could not be loaded");
    EXPECT_TRUE(sim_.WaitForDisconnect(subscriber_.client));
  }

  SimStandIn sim_;  // first: outlives the transport and every frame it holds
  std::unique_ptr<transport::Transport> transport_;
  SocketClient client_;
  Subscriber subscriber_;
};

// The ordering test every socket transport runs: `rounds` of "reply i, then
// frame i" from a stand-in sim thread, read by `client` (anything with
// ReceiveEnvelope). Every reply arrives, in order, and no frame before the
// reply offered ahead of it.
template <typename SocketClient>
void ExpectRepliesInOrderBeforeLaterFrames(SimStandIn& sim, session::ClientLink& link, SocketClient& client,
                                           uint64_t rounds) {
  std::atomic<uint64_t> replies_seen{0};
  const auto sim_thread = OfferRepliesThenFrames(sim, link, rounds, replies_seen);
  uint64_t frames = 0, last_frame = 0;
  while (replies_seen < rounds || last_frame < rounds) {
    proto::Envelope envelope;
    if (!client.ReceiveEnvelope(envelope, 5000ms)) {
      std::string counters;
      for (const auto& [name, value] : sim.context().counters.Snapshot()) counters += " " + name + "=" + std::to_string(value);
      FAIL() << "after reply " << replies_seen << ", frame " << last_frame << "; counters:" << counters;
    }
    if (envelope.has_state()) {
      ASSERT_EQ(envelope.state().frame_id(), replies_seen + 1) << "a reply was lost or reordered";
      EXPECT_EQ(envelope.sequence(), 0u) << "the daemon never sets Envelope.sequence";
      ++replies_seen;
      continue;
    }
    ASSERT_TRUE(envelope.has_frame()) << envelope.DebugString();
    ASSERT_LE(envelope.frame().frame_id(), replies_seen.load())
        << "frame " << envelope.frame().frame_id() << " overtook the reply offered before it";
    EXPECT_EQ(envelope.frame().camera(), "uav");
    last_frame = envelope.frame().frame_id();
    ++frames;
  }
  EXPECT_GT(frames, 0u);
}

}  // namespace sim4cv::test
