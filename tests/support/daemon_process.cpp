#include "tests/support/daemon_process.h"

#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <thread>

namespace sim4cv::testing {
namespace {

int DecodeWaitStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

}  // namespace

std::string ListeningField(const std::string& line, const std::string& key) {
  std::istringstream words(line);
  std::string word;
  const std::string prefix = key + "=";
  while (words >> word) {
    if (word.rfind(prefix, 0) == 0) return word.substr(prefix.size());
  }
  return "";
}

DaemonProcess::DaemonProcess(std::vector<std::string> args) {
  bool has_port = false;
  for (const auto& a : args) has_port = has_port || a == "--tcp-port";
  if (!has_port) {
    args.push_back("--tcp-port");
    args.push_back("0");
  }
  char path_template[] = "/tmp/sim4cvd-stderr-XXXXXX";
  const int stderr_fd = mkstemp(path_template);
  if (stderr_fd < 0) throw std::runtime_error("mkstemp failed");
  stderr_path_ = path_template;
  int out_pipe[2];
  if (pipe(out_pipe) != 0) throw std::runtime_error("pipe failed");

  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork failed");
  if (pid_ == 0) {
    dup2(out_pipe[1], STDOUT_FILENO);
    dup2(stderr_fd, STDERR_FILENO);
    close(out_pipe[0]);
    close(out_pipe[1]);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(SIM4CVD_PATH));
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(SIM4CVD_PATH, argv.data());
    _exit(127);
  }
  close(stderr_fd);
  close(out_pipe[1]);

  // Read stdout until the listening line or a deadline.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  std::string out;
  while (listening_line_.empty()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd pfd{out_pipe[0], POLLIN, 0};
    if (poll(&pfd, 1, static_cast<int>(left.count())) <= 0) break;
    char buf[512];
    const ssize_t n = read(out_pipe[0], buf, sizeof buf);
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
    const auto newline = out.find('\n');
    if (newline != std::string::npos) listening_line_ = out.substr(0, newline);
  }
  close(out_pipe[0]);  // the daemon prints nothing else on stdout
  if (listening_line_.rfind("sim4cvd listening", 0) != 0) {
    Stop(2000);
    throw std::runtime_error("sim4cvd did not print its listening line; got '" + out + "'; stderr:\n" + stderr_text());
  }
  tcp_port_ = static_cast<uint16_t>(std::stoi(ListeningField(listening_line_, "tcp")));
}

DaemonProcess::~DaemonProcess() {
  if (running()) {
    kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  if (!stderr_path_.empty()) unlink(stderr_path_.c_str());
}

bool DaemonProcess::running() {
  if (pid_ <= 0 || exit_status_ != -1) return false;
  int status = 0;
  const pid_t r = waitpid(pid_, &status, WNOHANG);
  if (r == pid_) {
    exit_status_ = DecodeWaitStatus(status);
    return false;
  }
  return r == 0;
}

std::size_t DaemonProcess::rss_bytes() const {
  std::ifstream status("/proc/" + std::to_string(pid_) + "/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stoull(line.substr(6)) * 1024;  // "VmRSS:  1234 kB"
  }
  return 0;
}

int DaemonProcess::open_fds() const {
  DIR* dir = opendir(("/proc/" + std::to_string(pid_) + "/fd").c_str());
  if (!dir) return -1;
  int count = 0;
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] != '.') ++count;
  }
  closedir(dir);
  return count;
}

int DaemonProcess::Stop(int timeout_ms) {
  if (!running()) return exit_status_;
  kill(pid_, SIGTERM);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!running()) return exit_status_;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(pid_, SIGKILL);
  int status = 0;
  waitpid(pid_, &status, 0);
  exit_status_ = -1;
  pid_ = -1;
  return -1;
}

std::string DaemonProcess::stderr_text() const {
  std::ifstream in(stderr_path_);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> DaemonProcess::warning_lines() const {
  // The log writes "[SECONDS] LEVEL TEXT", the level padded to 5 characters.
  std::vector<std::string> lines;
  std::istringstream text(stderr_text());
  for (std::string line; std::getline(text, line);) {
    if (line.find("] WARN ") != std::string::npos || line.find("] ERROR ") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

}  // namespace sim4cv::testing

namespace sim4cv::testing {

std::string DaemonProcess::access_token() const {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  const char* home = std::getenv("HOME");
  const std::string folder = runtime != nullptr && *runtime == '/' ? std::string(runtime) + "/sim4cv"
                                                                   : std::string(home ? home : "/tmp") + "/.cache/sim4cv";
  std::ifstream file(folder + "/tcp-" + std::to_string(tcp_port_) + ".token");
  std::string token;
  std::getline(file, token);
  return token;
}

}  // namespace sim4cv::testing
