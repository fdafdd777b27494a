// A daemon with the shared-memory transport on, under a name unique to this
// test process, plus helpers shared by the shm integration tests.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "sim4cv/shm_client.h"
#include "tests/integration/daemon_fixture.h"

namespace sim4cv::testing {

class ShmDaemonTest : public DaemonTest {
 protected:
  ShmDaemonTest() {
    static int counter = 0;
    shm_name_ = "/sim4cv-it-" + std::to_string(getpid()) + "-" + std::to_string(++counter);
  }

  void StartShmDaemon(std::vector<std::string> args = {}) {
    args.insert(args.end(), {"--shm-name", shm_name_});
    StartDaemon(std::move(args));
  }

  std::unique_ptr<ShmClient> OpenShm() {
    auto client = std::make_unique<ShmClient>();
    client->Open(shm_name_);
    return client;
  }

  // Sends GetStats over TCP and returns one counter.
  static uint64_t Counter(Client& tcp, const std::string& name) {
    proto::Envelope request;
    request.mutable_get_stats();
    tcp.SendEnvelope(request);
    proto::Envelope reply;
    while (tcp.ReceiveEnvelope(reply, std::chrono::milliseconds(5000))) {
      if (!reply.has_stats()) continue;
      const auto& counters = reply.stats().counters();
      const auto it = counters.find(name);
      return it == counters.end() ? 0 : it->second;
    }
    ADD_FAILURE() << "no Stats reply";
    return 0;
  }

  std::string shm_name_;
};

inline double Speed(const ShmEntityPose& pose) {
  return std::hypot(pose.linear_velocity[0], pose.linear_velocity[1], pose.linear_velocity[2]);
}

// Runs `body` in a child process; returns its exit code (-1 if it died of a signal).
template <typename Body>
inline int InChild(Body body) {
  const pid_t pid = fork();
  if (pid == 0) {
    int code = 99;
    try {
      code = body();
    } catch (const std::exception& error) {
      std::fprintf(stderr, "child: %s\n", error.what());
      code = 98;
    }
    _exit(code);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace sim4cv::testing
