// The studio's authoring requests, off the sim thread: CheckMap,
// GenerateMap (the seeded generator: up to a second for a large grid),
// SaveMap (written and fsync'ed), OpenMap and ListMaps (directory walks)
// touch no world state, so the sim thread hands them here and steps on; a
// worker thread of lower priority answers each through the client's link,
// its Configured.world taken from the WorldDirectory (the world as last
// published). Three clients pipelining GenerateMap once made every lockstep
// client wait over a second per frame.
#pragma once

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "server/daemon/config.h"
#include "server/session/command.h"
#include "server/session/server_context.h"

namespace sim4cv::daemon {

class AuthoringWorker {
 public:
  AuthoringWorker(const Config& config, session::WorldDirectory& directory);
  ~AuthoringWorker();  // answers nothing more; joins the thread
  AuthoringWorker(const AuthoringWorker&) = delete;
  AuthoringWorker& operator=(const AuthoringWorker&) = delete;

  // Whether `request` is one this worker carries out.
  static bool Handles(const proto::Configure& request);

  // Queues `command` (one Handles accepts). The queue needs no bound of its
  // own: each connection has at most limits::kMaxOutstandingConfigures
  // Configures unanswered.
  void Post(session::ConfigureCommand command);

 private:
  void Run();
  void Answer(session::ConfigureCommand& command);

  const Config& config_;
  session::WorldDirectory& directory_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<session::ConfigureCommand> queue_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace sim4cv::daemon
