// The daemon's own RunDaemon in the test's process, for worked examples that
// are linked into the daemon (a transport, an entity kind): started with
// flags and an access token, its listening line read from its stdout, and
// stopped by a SIGTERM to its thread as sim4cvd is.
#pragma once

#include <gtest/gtest.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "server/daemon/daemon.h"

namespace sim4cv::testing {

class InProcessDaemon {
 public:
  static constexpr const char* kToken = "0123456789abcdef0123456789abcdef";

  explicit InProcessDaemon(std::vector<std::string> flags)
      : folder_(std::filesystem::temp_directory_path() / ("sim4cv-in-process-" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(folder_);
    std::ofstream(folder_ / "token") << kToken << "\n";
    flags.insert(flags.end(), {"--token-file", (folder_ / "token").string()});
    std::string help;
    const auto config = daemon::ParseFlags(flags, help);
    if (!config) throw std::invalid_argument("flags the daemon does not take");
    // The daemon blocks SIGINT/SIGTERM in its thread to wait for them; so does this one.
    sigset_t stop;
    sigemptyset(&stop);
    sigaddset(&stop, SIGINT);
    sigaddset(&stop, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop, nullptr);
    int out[2];
    if (::pipe(out) != 0) throw std::runtime_error("pipe");
    std::fflush(stdout);
    const int saved_stdout = ::dup(1);
    ::dup2(out[1], 1);
    std::packaged_task<int()> run([config = *config] { return daemon::RunDaemon(config); });
    exit_status_ = run.get_future();
    thread_ = std::thread(std::move(run));
    listening_ = ReadLine(out[0]);
    std::fflush(stdout);
    ::dup2(saved_stdout, 1);
    for (int fd : {saved_stdout, out[0], out[1]}) ::close(fd);
    std::smatch port;
    if (std::regex_search(listening_, port, std::regex("tcp=(\\d+)"))) tcp_port_ = std::stoi(port[1]);
  }
  ~InProcessDaemon() {
    if (thread_.joinable()) Stop();
    std::filesystem::remove_all(folder_);
  }

  // "sim4cvd listening tcp=PORT ...", as the daemon printed it.
  const std::string& listening_line() const { return listening_; }
  uint16_t tcp_port() const { return static_cast<uint16_t>(tcp_port_); }
  // SIGTERM, then the daemon's exit status.
  int Stop() {
    pthread_kill(thread_.native_handle(), SIGTERM);
    thread_.join();
    return exit_status_.get();
  }

 private:
  // One line from `fd`, waiting at most two minutes (the daemon builds its world first).
  static std::string ReadLine(int fd) {
    std::string line;
    char c = 0;
    pollfd ready{fd, POLLIN, 0};
    while (::poll(&ready, 1, 120000) == 1 && ::read(fd, &c, 1) == 1 && c != '\n') line += c;
    return line;
  }

  std::filesystem::path folder_;
  std::future<int> exit_status_;
  std::thread thread_;
  std::string listening_;
  int tcp_port_ = 0;
};

}  // namespace sim4cv::testing
