// Runs the real sim4cvd as a separate process on loopback for integration
// tests (gz-transport's two-process tests): port 0, the listening line parsed
// from its stdout, its stderr kept in a file for failure messages.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sim4cv::testing {

class DaemonProcess {
 public:
  // Starts sim4cvd with `args` (plus --tcp-port 0 unless given) and waits up to
  // 20 s for its listening line. Throws std::runtime_error on failure.
  explicit DaemonProcess(std::vector<std::string> args = {});
  ~DaemonProcess();  // SIGKILL if still running
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  uint16_t tcp_port() const { return tcp_port_; }
  // The access token clients must show in Hello (docs/security.md), read
  // from the file the daemon wrote for its TCP port, as the clients do.
  std::string access_token() const;
  // The whole listening line, e.g. "sim4cvd listening tcp=40123".
  const std::string& listening_line() const { return listening_line_; }
  pid_t pid() const { return pid_; }
  bool running();
  // SIGTERM, then wait up to `timeout_ms`; returns the exit status (or -1 if it
  // had to be killed, 128+N if it died of signal N).
  int Stop(int timeout_ms = 10000);
  // Everything the daemon wrote to stderr so far.
  std::string stderr_text() const;
  // The lines of stderr_text() the daemon's log wrote at warning or error level.
  std::vector<std::string> warning_lines() const;
  // The daemon's resident memory (VmRSS) and its open file descriptors now,
  // for tests that check what a client can make it hold; 0 / -1 if gone.
  std::size_t rss_bytes() const;
  int open_fds() const;

 private:
  pid_t pid_ = -1;
  int exit_status_ = -1;
  uint16_t tcp_port_ = 0;
  std::string listening_line_;
  std::string stderr_path_;
};

// The value of `key=` in a listening line, or "" if absent.
std::string ListeningField(const std::string& line, const std::string& key);

}  // namespace sim4cv::testing
