// Starts sim4cvd as a separate process that is expected to refuse its start
// (exit status 2 with a message), for the tests of what the daemon checks
// before it listens: files named by its flags.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace sim4cv::testing {

// The exit status and stderr of sim4cvd started with `args` (and, if given,
// that RLIMIT_NOFILE), waiting at most 20 s (then SIGKILL: status -1).
inline std::pair<int, std::string> RunToExit(const std::vector<std::string>& args,
                                             std::optional<rlimit> descriptors = std::nullopt) {
  char path[] = "/tmp/sim4cvd-exit-XXXXXX";
  const int err = mkstemp(path);
  const pid_t pid = fork();
  if (pid == 0) {
    if (descriptors) setrlimit(RLIMIT_NOFILE, &*descriptors);
    dup2(err, STDERR_FILENO);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    std::vector<char*> argv{const_cast<char*>(SIM4CVD_PATH)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(SIM4CVD_PATH, argv.data());
    _exit(127);
  }
  close(err);
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  bool killed = false;
  while (waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      killed = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  unlink(path);
  return {killed || !WIFEXITED(status) ? -1 : WEXITSTATUS(status), text};
}

}  // namespace sim4cv::testing
