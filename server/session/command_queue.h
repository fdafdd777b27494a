// Many transport threads post, the sim thread drains once per step.
#pragma once

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <vector>

#include "server/common/limits.h"
#include "server/session/command.h"

namespace sim4cv::session {

class CommandQueue {
 public:
  // For commands bounded elsewhere (Steps by each client's backlog,
  // Configures by its outstanding requests, one Subscribe per reply, one
  // Disconnect): always queued.
  void Post(Command command) {
    {
      std::lock_guard lock(mutex_);
      pending_.push_back(std::move(command));
    }
    ready_.notify_one();
  }

  // For commands a client may send without waiting for anything (Controls,
  // TrackerOutput): queued only while fewer than limits::kMaxQueuedCommands
  // wait, so a flood while the sim thread is busy (a LoadMap) cannot grow the
  // queue without bound. False: dropped; the caller tells the client.
  bool TryPost(Command command) {
    {
      std::lock_guard lock(mutex_);
      if (pending_.size() >= limits::kMaxQueuedCommands) return false;
      pending_.push_back(std::move(command));
    }
    ready_.notify_one();
    return true;
  }

  // Moves every pending command into `out` (cleared first). Swapping vectors
  // keeps both buffers' capacity, so steady-state draining allocates nothing.
  // A burst's capacity is given back: a buffer grown past kKeptCommands is
  // replaced when it comes back empty, so both shrink within two drains.
  void Drain(std::vector<Command>& out) {
    out.clear();
    if (out.capacity() > kKeptCommands) std::vector<Command>().swap(out);
    std::lock_guard lock(mutex_);
    std::swap(out, pending_);
  }

  static constexpr std::size_t kKeptCommands = 1024;

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
