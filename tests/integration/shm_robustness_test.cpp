// The shared-memory transport when clients misbehave or vanish: readers that
// die mid-read or never release a view, lockstep clients that go silent,
// refused messages; and the object's life cycle (removed on SIGTERM, a stale
// one replaced at start).
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

// Forks a child that maps the ring and then dies in `how`; returns its exit status.
template <typename Body>
int InChild(Body body) {
  const pid_t pid = fork();
  if (pid == 0) {
    body();
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return status;
}

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
  });
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child status " << status;
  // Another is killed while it sleeps in WaitForFrame (it leaves frame_waiters raised).
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
  StartShmDaemon({"--shm-expiry-ms", "600"});
  auto tcp = Connect("tcp-lockstep");
  tcp->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  auto shm = OpenShm();
  shm->Hello("goes-silent");
  shm->Subscribe(proto::DELIVERY_LOCKSTEP);
  shm->Step();
  tcp->Step();
  proto::Frame frame;
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 5000ms)) << "both lockstep clients stepped";
  // Now the shm client stops sending: the TCP client's Step waits for it ...
  const auto start = std::chrono::steady_clock::now();
  tcp->Step();
  EXPECT_FALSE(tcp->ReceiveFrame(frame, 200ms));
  // ... until the daemon gives up on it.
  ASSERT_TRUE(tcp->ReceiveFrame(frame, 5000ms));
  const auto waited = std::chrono::steady_clock::now() - start;
  EXPECT_GE(waited, 400ms);
  EXPECT_LT(waited, 3000ms);
  EXPECT_EQ(Counter(*tcp, "shm.clients_expired"), 1u);
  proto::Envelope reply;
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

TEST_F(ShmDaemonTest, ObjectIsRemovedOnSigterm) {
  StartShmDaemon();
  auto shm = OpenShm();
  EXPECT_FALSE(shm->closed());
  EXPECT_EQ(daemon_->Stop(), 0) << daemon_->stderr_text();
  daemon_.reset();
  EXPECT_TRUE(shm->closed()) << "the daemon marks the ring closed before it goes";
  EXPECT_THROW(shm->WaitForFrame(0, 1000ms), ConnectionError);
  const int fd = shm_open(shm_name_.c_str(), O_RDONLY, 0);
  EXPECT_LT(fd, 0) << shm_name_ << " still exists after SIGTERM";
  EXPECT_EQ(errno, ENOENT);
  if (fd >= 0) close(fd);
}

TEST_F(ShmDaemonTest, StaleObjectIsReplacedAtStart) {
  const int fd = shm_open(shm_name_.c_str(), O_CREAT | O_RDWR | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  const std::string garbage(10000, '\x5a');
  ASSERT_EQ(write(fd, garbage.data(), garbage.size()), static_cast<ssize_t>(garbage.size()));
  close(fd);
  {
    ShmClient client;
    EXPECT_THROW(client.Open(shm_name_), ShmError);
  }
  StartShmDaemon({"--mode", "realtime"});
  auto shm = OpenShm();
  EXPECT_EQ(shm->header().writer_pid, static_cast<uint32_t>(daemon_->pid()));
  ASSERT_TRUE(shm->WaitForFrame(0, 5000ms)) << "realtime: the ring's own subscription renders every frame";
  EXPECT_NE(daemon_->stderr_text().find("replaced the stale shared-memory object " + shm_name_), std::string::npos)
      << daemon_->stderr_text();
}

}  // namespace
}  // namespace sim4cv::testing
