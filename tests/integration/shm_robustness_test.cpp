// The shared-memory transport when clients misbehave or vanish: readers that
// die mid-read or never release a view, lockstep clients that go silent or
// die, refused messages; and the life cycle (the ring closed and the socket
// gone on SIGTERM, a second daemon with the same name refused at start).
// Hostile clients: shm_hostile_test.cpp.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "tests/integration/shm_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;


TEST_F(ShmDaemonTest, ReadersThatDieMidReadDoNotAffectTheDaemon) {
  StartShmDaemon();
  auto tcp = Connect();
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  tcp->StepAndReceive();
  // A child dies holding a zero-copy view, halfway through its pixels.
  const int status = InChild([&] {
    ShmClient child;
    child.Open(shm_name_);
    FrameView view;
    if (!child.AcquireNewest(view)) _exit(3);
    volatile uint8_t sum = 0;
    for (uint32_t i = 0; i < view.width() * view.height(); ++i)
      sum = static_cast<uint8_t>(sum + view.image(proto::CHANNEL_RGB)->data[i]);
    _exit(0);  // no Release, no Close
    return 0;
  });
  EXPECT_EQ(status, 0) << "child exit code";
  // Another is killed while it sleeps in WaitForFrame.
  const pid_t waiter = fork();
  if (waiter == 0) {
    ShmClient child;
    child.Open(shm_name_);
    child.WaitForFrame(UINT64_MAX - 1, 60000ms);
    _exit(0);
  }
  std::this_thread::sleep_for(200ms);
  kill(waiter, SIGKILL);
  waitpid(waiter, nullptr, 0);

  auto shm = OpenShm();
  for (int i = 0; i < 5; ++i) {
    const uint64_t id = tcp->StepAndReceive().frame_id();
    ASSERT_TRUE(shm->WaitForFrame(id - 1, 5000ms));
    EXPECT_EQ(shm->newest_frame_id(), id);
  }
  EXPECT_TRUE(daemon_->running());
}

TEST_F(ShmDaemonTest, UnreleasedViewGoesStaleAndNeverBlocksTheWriter) {
  StartShmDaemon({"--shm-slots", "3"});
  auto tcp = Connect();
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  auto shm = OpenShm();
  tcp->StepAndReceive();
  ASSERT_TRUE(shm->WaitForFrame(0, 5000ms));
  FrameView view;
  ASSERT_TRUE(shm->AcquireNewest(view));
  ASSERT_EQ(view.frame_id(), 1u);
  for (int i = 0; i < 2; ++i) tcp->StepAndReceive();
  ASSERT_TRUE(shm->WaitForFrame(2, 5000ms));
  EXPECT_FALSE(view.stale()) << "two more frames fit in the other two slots";
  // The writer reuses the view's slot without waiting, and keeps going.
  for (int i = 0; i < 10; ++i) tcp->StepAndReceive();
  ASSERT_TRUE(shm->WaitForFrame(12, 5000ms));
  EXPECT_TRUE(view.stale());
  EXPECT_THROW(view.Validate(), ShmError);
  EXPECT_EQ(view.frame_id(), 1u);
  FrameView fresh;
  ASSERT_TRUE(shm->AcquireNewest(fresh));
  EXPECT_EQ(fresh.frame_id(), 13u);
  EXPECT_FALSE(fresh.stale());
}

TEST_F(ShmDaemonTest, SilentLockstepClientIsDisconnected) {
  // 2 s: room for a busy machine to pause this test between the shm
  // client's Hello, Subscribe and Step without the attachment lapsing.
  StartShmDaemon({"--shm-expiry-ms", "2000"});
  auto tcp = Connect("tcp-lockstep");
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  auto shm = OpenShm();
  shm->Hello("goes-silent");
  shm->Subscribe(proto::DELIVERY_LOCKSTEP);
  // The expiry counts from the shm client's last message, this Step: timing
  // from before it gives a lower bound a loaded machine cannot break.
  const auto start = std::chrono::steady_clock::now();
  shm->Step();
  tcp->Step();
  proto::Frame frame;
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 5000ms)) << "both lockstep clients stepped";
  // Now the shm client stops sending: the TCP client's Step waits for it ...
  tcp->Step();
  EXPECT_FALSE(tcp->ReceiveFrame(frame, 200ms));
  // ... until the daemon gives up on it.
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 60000ms));
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, 2000ms);
  EXPECT_LT(waited, 30000ms);  // the daemon gave up on it (margin for a busy host), not never
  EXPECT_EQ(Counter(*tcp, "shm.clients_expired"), 1u);
  // Its last response says why; then the attachment is over.
  proto::Envelope reply;
  ASSERT_TRUE(shm->ReceiveReply(reply, 1000ms));
  ASSERT_TRUE(reply.has_error()) << reply.DebugString();
  EXPECT_TRUE(reply.error().fatal());
  EXPECT_NE(reply.error().message().find("--shm-expiry-ms"), std::string::npos) << reply.error().message();
  EXPECT_FALSE(shm->attached());
  EXPECT_THROW(shm->ReceiveReply(reply, 1000ms), ConnectionError);
  // It may come back with a new Hello.
  EXPECT_GT(shm->Hello("back").client_id(), 0u);
}

TEST_F(ShmDaemonTest, RefusalsComeBackThroughTheResponseArea) {
  StartShmDaemon();
  auto shm = OpenShm();
  try {
    shm->Hello("old", 5000ms, 99);
    FAIL() << "version 99 accepted";
  } catch (const ServerError& error) {
    EXPECT_EQ(error.code(), proto::ERROR_CODE_VERSION_MISMATCH);
    EXPECT_TRUE(error.fatal());
    EXPECT_NE(std::string(error.what()).find("99"), std::string::npos) << error.what();
  }
  shm->Hello("fixed");  // a new session for the same token
  proto::Envelope subscribe;
  subscribe.mutable_subscribe()->set_camera("nope");
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_RGB);
  subscribe.mutable_subscribe()->set_delivery(proto::DELIVERY_NEWEST);
  shm->SendEnvelope(subscribe);
  proto::Envelope reply;
  ASSERT_TRUE(shm->ReceiveReply(reply, 5000ms));
  ASSERT_TRUE(reply.has_error()) << reply.DebugString();
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_UNKNOWN_CAMERA);
  EXPECT_FALSE(reply.error().fatal());
  shm->Step();  // no lockstep subscription
  ASSERT_TRUE(shm->ReceiveReply(reply, 5000ms));
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_INVALID_STATE);
  const char garbage[] = "\xff\xff\xff\xff not protobuf";
  shm->SendRaw(garbage, sizeof garbage);
  ASSERT_TRUE(shm->ReceiveReply(reply, 5000ms));
  EXPECT_EQ(reply.error().code(), proto::ERROR_CODE_MALFORMED_MESSAGE);
  EXPECT_TRUE(reply.error().fatal());
}

// A lockstep client that dies holds nobody back: the daemon learns it from
// its socket at once, long before --shm-expiry-ms.
TEST_F(ShmDaemonTest, LockstepClientThatDiesIsForgottenAtOnce) {
  StartShmDaemon({"--shm-expiry-ms", "60000"});
  auto tcp = Connect("tcp-lockstep");
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  int ready[2];
  ASSERT_EQ(pipe(ready), 0);
  const pid_t child = fork();
  if (child == 0) {
    ShmClient shm;
    shm.Open(shm_name_);
    shm.Hello("dies");
    shm.Subscribe(proto::DELIVERY_LOCKSTEP);
    [[maybe_unused]] const auto n = write(ready[1], "x", 1);
    pause();  // holds the simulation until killed
    _exit(0);
  }
  char byte;
  ASSERT_EQ(read(ready[0], &byte, 1), 1);
  tcp->Step();
  proto::Frame frame;
  EXPECT_FALSE(tcp->ReceiveFrame(frame, 300ms)) << "the shm lockstep client has not stepped";
  const auto start = std::chrono::steady_clock::now();
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 10000ms));
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5000ms) << "not the 60 s expiry";
  EXPECT_EQ(Counter(*tcp, "shm.clients_expired"), 0u);
  close(ready[0]);
  close(ready[1]);
}

TEST_F(ShmDaemonTest, RingIsClosedAndNameFreedOnSigterm) {
  StartShmDaemon();
  auto shm = OpenShm();
  shm->Hello("stays");
  EXPECT_FALSE(shm->closed());
  EXPECT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
  daemon_.reset();
  EXPECT_TRUE(shm->closed()) << "the daemon marks the ring closed before it goes";
  EXPECT_FALSE(shm->attached());
  EXPECT_THROW(shm->WaitForFrame(0, 1000ms), ConnectionError);
  ShmClient late;
  try {
    late.Open(shm_name_);
    ADD_FAILURE() << "attached to a daemon that stopped";
  } catch (const ShmError& error) {
    EXPECT_NE(std::string(error.what()).find("no sim4cvd serves shared memory under " + shm_name_),
              std::string::npos)
        << error.what();
  }
  // The name is free again: a new daemon takes it.
  StartShmDaemon();
  EXPECT_NO_THROW(OpenShm()->Hello("next"));
}

TEST_F(ShmDaemonTest, SecondDaemonWithTheSameNameIsRefusedAtStart) {
  StartShmDaemon();
  try {
    DaemonProcess second({"--shm-name", shm_name_});
    ADD_FAILURE() << "a second daemon started with the same --shm-name";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("another sim4cvd serves this --shm-name"), std::string::npos)
        << error.what();
  }
  auto shm = OpenShm();
  EXPECT_EQ(shm->header().writer_pid, static_cast<uint32_t>(daemon_->pid())) << "the first still serves it";
  EXPECT_GT(shm->Hello("first").client_id(), 0u);
}

}  // namespace
}  // namespace sim4cv::testing
