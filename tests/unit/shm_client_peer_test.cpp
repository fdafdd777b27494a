// The C++ shared-memory client attaches only to a socket served by a process
// of its own user: the abstract socket name is anyone's to take, and a
// process of another user listening there must get nothing (the Octave
// client attaches through this code too).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <string>

#include "protocol/shm_sync.h"
#include "sim4cv/shm_client.h"

namespace sim4cv {
namespace {

constexpr uid_t kNobody = 65534;

// A child of user nobody that listens on the socket of shm name `name`
// until killed; its pid once it listens.
pid_t ListenAsNobody(const std::string& name) {
  int ready[2];
  if (pipe(ready) != 0) return -1;
  const pid_t child = fork();
  if (child == 0) {
    close(ready[0]);
    if (setgid(kNobody) != 0 || setuid(kNobody) != 0) _exit(10);
    const int fd = socket(AF_UNIX, SOCK_SEQPACKET, 0);
    const std::string path = shm::SocketPath(name);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::memcpy(address.sun_path, path.data(), path.size());
    const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
    if (fd < 0 || bind(fd, reinterpret_cast<sockaddr*>(&address), length) != 0 || listen(fd, 4) != 0) _exit(11);
    if (write(ready[1], "r", 1) != 1) _exit(12);
    sleep(30);  // killed by the test long before
    _exit(0);
  }
  close(ready[1]);
  char byte = 0;
  const bool listening = read(ready[0], &byte, 1) == 1;
  close(ready[0]);
  return listening ? child : -1;
}

TEST(ShmClientPeerTest, ASocketOfAnotherUserIsRefused) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to run a process as nobody";
  const std::string name = "/hostile-owner-" + std::to_string(getpid());
  const pid_t fake = ListenAsNobody(name);
  ASSERT_GT(fake, 0) << "the fake daemon could not listen as nobody";
  std::string message;
  try {
    ShmClient client;
    client.Open(name);
  } catch (const ShmError& error) {
    message = error.what();
  }
  kill(fake, SIGKILL);
  waitpid(fake, nullptr, 0);
  EXPECT_NE(message.find("refusing to attach to " + name + ": the socket @sim4cv-shm" + name + " belongs to process " +
                         std::to_string(fake) + " of uid 65534, not to this user (uid 0)"),
            std::string::npos)
      << (message.empty() ? "attached to a socket of user nobody" : message);
}

}  // namespace
}  // namespace sim4cv
