// Hostile shared-memory clients against the real daemon. Each attack runs in
// a forked child, the daemon in its own process; after
// (or during) each one the daemon is still running, another shm client still
// gets every frame and its replies within a bound, and a TCP client is
// unaffected. The attacks: random stores everywhere a client can write
// (its own area, including every index and size the daemon reads), attempts
// to write the frame object, ftruncate/fallocate of every descriptor the
// client was given and of the daemon's own memfd through /proc, unlinking
// and squatting the name, and a request flood.
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <thread>

#include "protocol/shm_sync.h"
#include "tests/integration/shm_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;


// A failed call with the expected errno, or a numbered exit code for the child.
#define CHILD_EXPECT_FAILS(call, error, code) \
  do {                                       \
    errno = 0;                               \
    if ((call) != -1 || errno != (error)) return code; \
  } while (0)

class ShmHostileTest : public ShmDaemonTest {
 protected:
  void SetUp() override {
    StartShmDaemon();
    tcp_ = Connect("tcp-lockstep");
    tcp_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
    observer_ = OpenShm();
    observer_->Hello("observer");
  }

  // What every attack must leave intact: the daemon runs, the TCP client's
  // Steps give frames, the observer sees each of them in the ring and gets a
  // GetState answered within a bound.
  void ExpectOthersUnaffected(int frames = 3) {
    ASSERT_TRUE(daemon_->running()) << daemon_->stderr_text();
    for (int i = 0; i < frames; ++i) {
      const uint64_t id = tcp_->StepAndReceive(10000ms).frame_id();
      ASSERT_TRUE(observer_->WaitForFrame(id - 1, 5000ms)) << "frame " << id << " not in the ring";
      OwnedFrame frame;
      ASSERT_TRUE(observer_->ReadNewest(frame));
      EXPECT_EQ(frame.frame_id, id);
      EXPECT_EQ(frame.planes[0].size(), static_cast<std::size_t>(320 * 180 * 3));  // RGB
      const auto start = std::chrono::steady_clock::now();
      const proto::State state = observer_->GetState(60000ms);
      EXPECT_LT(std::chrono::steady_clock::now() - start, 30000ms);  // answered, with a margin for busy hosts
      EXPECT_EQ(state.frame_id(), id);
    }
    EXPECT_EQ(tcp_->GetState().frame_id(), observer_->newest_frame_id());
    EXPECT_TRUE(daemon_->running());
  }

  std::unique_ptr<Client> tcp_;
  std::unique_ptr<ShmClient> observer_;
};

TEST_F(ShmHostileTest, FrameObjectCannotBeWrittenShrunkOrGrown) {
  const int code = InChild([&] {
    ShmClient shm;
    shm.Open(shm_name_);
    const int fd = shm.frames_fd();
    const std::size_t size = shm.header().total_bytes;
    // Writable mappings, write(), mprotect of the read-only mapping: all refused by the seals.
    errno = 0;
    if (mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0) != MAP_FAILED || errno != EPERM) return 10;
    CHILD_EXPECT_FAILS(pwrite(fd, "x", 1, 200), EPERM, 11);
    void* mapped = const_cast<shm::ShmHeader*>(&shm.header());
    CHILD_EXPECT_FAILS(mprotect(mapped, 4096, PROT_READ | PROT_WRITE), EACCES, 12);
    // The layout fields the old design trusted cannot be stored to: the page is read-only.
    CHILD_EXPECT_FAILS(ftruncate(fd, 0), EPERM, 13);
    CHILD_EXPECT_FAILS(ftruncate(fd, static_cast<off_t>(size / 2)), EPERM, 14);
    CHILD_EXPECT_FAILS(ftruncate(fd, static_cast<off_t>(size * 2)), EPERM, 15);
    CHILD_EXPECT_FAILS(fallocate(fd, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, 0, static_cast<off_t>(size)), EPERM,
                       16);
    CHILD_EXPECT_FAILS(fcntl(fd, F_ADD_SEALS, F_SEAL_WRITE), EPERM, 17);
    // Reopening it read-write through /proc does not lift the seals either.
    const int again = open(("/proc/self/fd/" + std::to_string(fd)).c_str(), O_RDWR);
    if (again < 0) return 18;
    CHILD_EXPECT_FAILS(ftruncate(again, 0), EPERM, 19);
    errno = 0;
    if (mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, again, 0) != MAP_FAILED || errno != EPERM) return 20;
    return 0;
  });
  EXPECT_EQ(code, 0) << "step " << code << " of the child was not refused";
  ExpectOthersUnaffected();
}

TEST_F(ShmHostileTest, DaemonsOwnMemfdCannotBeShrunkThroughProc) {
  const int code = InChild([&] {
    const std::string dir = "/proc/" + std::to_string(daemon_->pid()) + "/fd";
    DIR* fds = opendir(dir.c_str());
    if (!fds) return 30;
    int attacked = 0;
    while (const dirent* entry = readdir(fds)) {
      char target[256] = {};
      const std::string link = dir + "/" + entry->d_name;
      if (readlink(link.c_str(), target, sizeof target - 1) <= 0) continue;
      if (std::strstr(target, "memfd:sim4cv") == nullptr) continue;
      const int fd = open(link.c_str(), O_RDWR);  // root may open it read-write ...
      if (fd < 0) return 31;
      CHILD_EXPECT_FAILS(ftruncate(fd, 0), EPERM, 32);  // ... but not shrink it
      CHILD_EXPECT_FAILS(ftruncate(fd, 4096), EPERM, 33);
      close(fd);
      ++attacked;
    }
    closedir(fds);
    return attacked >= 1 ? 0 : 34;
  });
  EXPECT_EQ(code, 0) << "step " << code << " of the child failed";
  ExpectOthersUnaffected();
}

TEST_F(ShmHostileTest, TruncatingOrPunchingItsOwnAreaHurtsOnlyItself) {
  const int code = InChild([&] {
    ShmClient shm;
    shm.Open(shm_name_);
    shm.Hello("truncates");
    const int area = shm.area_fd();
    CHILD_EXPECT_FAILS(ftruncate(area, 0), EPERM, 40);
    CHILD_EXPECT_FAILS(ftruncate(area, 4096), EPERM, 41);
    CHILD_EXPECT_FAILS(ftruncate(area, static_cast<off_t>(shm::kAreaBytes * 2)), EPERM, 42);
    CHILD_EXPECT_FAILS(fcntl(area, F_ADD_SEALS, F_SEAL_FUTURE_WRITE), EPERM, 43);
    CHILD_EXPECT_FAILS(ftruncate(shm.doorbell_fd(), 0), EINVAL, 44);
    CHILD_EXPECT_FAILS(ftruncate(shm.socket_fd(), 0), EINVAL, 45);
    // Punching holes is allowed: the pages come back as zeros, for both sides.
    if (fallocate(area, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, 0, static_cast<off_t>(shm::kAreaBytes)) != 0)
      return 46;
    // The daemon answers into the punched pages without faulting; the client
    // lost its own counters, so at most it is told its ring is broken.
    try {
      shm.GetState(2000ms);
    } catch (const std::exception&) {
    }
    return 0;
  });
  EXPECT_EQ(code, 0) << "step " << code << " of the child failed";
  ExpectOthersUnaffected();
}

// Random stores all over the client's own area, and every field the daemon
// reads from it set to the values that broke the old design: request_write
// far ahead and behind, sizes of 2^32-1, while the child rings its doorbell
// as fast as it can and attaches again whenever the daemon drops it.
TEST_F(ShmHostileTest, RandomStoresIntoItsAreaWhileOthersWork) {
  const pid_t child = fork();
  if (child == 0) {
    std::mt19937_64 random(14);
    ShmClient shm;
    const auto end = std::chrono::steady_clock::now() + 20s;  // killed long before
    while (std::chrono::steady_clock::now() < end) {
      try {
        if (!shm.attached()) shm.Open(shm_name_);
        auto* area = reinterpret_cast<uint64_t*>(shm.area());
        auto& header = *reinterpret_cast<shm::ShmAreaHeader*>(shm.area());
        for (int i = 0; i < 64; ++i) area[random() % (shm::kAreaBytes / 8)] = random();
        switch (random() % 5) {
          case 0: header.request_write = header.request_read + (UINT64_MAX / 2); break;
          case 1: header.request_write = header.request_read - 1; break;
          case 2:
            reinterpret_cast<shm::ShmRequestSlot*>(shm.area() + shm::kAreaRequestOffset)->size = 0xffffffffu;
            header.request_write = header.request_read + 1;
            break;
          case 3: header.request_write = header.request_read + shm::kShmRequestCapacity; break;
          default: header.response_futex = static_cast<uint32_t>(random()); break;
        }
        const uint64_t one = 1;
        [[maybe_unused]] const auto n = write(shm.doorbell_fd(), &one, sizeof one);
      } catch (const std::exception&) {
        std::this_thread::sleep_for(1ms);
      }
    }
    _exit(0);
  }
  std::this_thread::sleep_for(200ms);  // let it get going
  ExpectOthersUnaffected(10);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  EXPECT_GT(Counter(*tcp_, "shm.rings_broken"), 0u) << "the attacks reached the daemon";
  ExpectOthersUnaffected();
  EXPECT_EQ(observer_->responses_lost(), 0u);
}

// A client that pipelines requests as fast as it can (GetState: each one
// answered) never reads: the observer's requests still go through, since the
// daemon takes at most one ring's worth from each client per turn.
TEST_F(ShmHostileTest, RequestFloodDoesNotDelayOtherClients) {
  const pid_t child = fork();
  if (child == 0) {
    ShmClient shm;
    shm.Open(shm_name_);
    shm.Hello("floods");
    proto::Envelope request;
    request.mutable_get_state();
    for (;;) shm.SendEnvelope(request);  // until killed (or throws when detached)
    _exit(0);
  }
  std::this_thread::sleep_for(200ms);
  ExpectOthersUnaffected(10);
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  ExpectOthersUnaffected();
}

TEST_F(ShmHostileTest, NameCannotBeUnlinkedOrTaken) {
  const int fds_before = daemon_->open_fds();
  const int code = InChild([&] {
    // No file backs the name: nothing to unlink.
    CHILD_EXPECT_FAILS(shm_unlink(shm_name_.c_str()), ENOENT, 50);
    CHILD_EXPECT_FAILS(unlink(("/dev/shm" + shm_name_).c_str()), ENOENT, 51);
    // The daemon holds the abstract socket: nobody can bind it meanwhile.
    const std::string path = shm::SocketPath(shm_name_);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, path.data(), path.size());
    const int squatter = socket(AF_UNIX, SOCK_SEQPACKET, 0);
    CHILD_EXPECT_FAILS(bind(squatter, reinterpret_cast<const sockaddr*>(&address),
                            static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size())),
                       EADDRINUSE, 52);
    // A client that attaches and closes its socket at once, many times. The
    // daemon frees a place when it sees the socket close, which may lag
    // behind a fast loop: a refusal for full places then means "wait".
    for (int i = 0; i < 200; ++i) {
      for (int attempt = 0;; ++attempt) {
        try {
          ShmClient brief;
          brief.Open(shm_name_);
          break;
        } catch (const std::exception& error) {
          if (attempt == 400 || std::string(error.what()).find("client places are in use") == std::string::npos) throw;
          std::this_thread::sleep_for(5ms);
        }
      }
    }
    return 0;
  });
  EXPECT_EQ(code, 0) << "step " << code << " of the child failed";
  // New clients still attach and are served.
  auto late = OpenShm();
  EXPECT_GT(late->Hello("late").client_id(), 0u);
  ExpectOthersUnaffected();
  // Every attachment that ended gave its descriptors back (the late one holds two).
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (daemon_->open_fds() > fds_before + 2 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  EXPECT_LE(daemon_->open_fds(), fds_before + 2);
}

}  // namespace
}  // namespace sim4cv::testing
