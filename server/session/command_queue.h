// Many transport threads post, the sim thread drains once per step.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "server/session/command.h"

namespace sim4cv::session {

class CommandQueue {
 public:
  void Post(Command command) {
    {
      std::lock_guard lock(mutex_);
      pending_.push_back(std::move(command));
    }
    ready_.notify_one();
  }

  // Moves every pending command into `out` (cleared first). Swapping vectors
  // keeps both buffers' capacity, so steady-state draining allocates nothing.
  void Drain(std::vector<Command>& out) {
    out.clear();
    std::lock_guard lock(mutex_);
    std::swap(out, pending_);
  }

  // Blocks until a command is pending, Wake() is called, or `deadline`.
  void WaitUntil(std::chrono::steady_clock::time_point deadline) {
    std::unique_lock lock(mutex_);
    ready_.wait_until(lock, deadline, [&] { return !pending_.empty() || woken_; });
    woken_ = false;
  }

  // Ends a WaitUntil early (shutdown).
  void Wake() {
    {
      std::lock_guard lock(mutex_);
      woken_ = true;
    }
    ready_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::vector<Command> pending_;
  bool woken_ = false;
};

}  // namespace sim4cv::session
