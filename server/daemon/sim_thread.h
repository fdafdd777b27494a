// The one thread that touches Bullet and OpenGL. Per step it drains the
// command queue (carrying out Configure requests and answering them),
// advances physics by a frame's worth of substeps, renders every camera
// someone subscribed to, hands the frames to the scheduler and, with --log,
// appends the frame's run-log record.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "server/daemon/authoring_worker.h"
#include "server/daemon/car_drivers.h"
#include "server/daemon/config.h"
#include "server/daemon/frame_assembler.h"
#include "server/daemon/run_logger.h"
#include "server/daemon/simulation.h"
#include "server/session/command_queue.h"
#include "server/session/scheduler.h"
#include "server/session/server_context.h"
#include "server/sim/world.h"

namespace sim4cv::render {
class GlContext;
}  // namespace sim4cv::render

namespace sim4cv::daemon {

class SimThread {
 public:
  // With config.replay_file, loads the replayed log; with config.log_file,
  // creates the run log. Throws naming the file if either cannot be.
  SimThread(const Config& config, std::shared_ptr<const sim::Scene> scene, session::CommandQueue& commands,
            session::LatestState& latest_state, session::WorldDirectory& directory, session::Counters& counters);
  ~SimThread();

  // Starts the thread and waits until its GL context and renderer exist;
  // rethrows what went wrong there.
  void Start();
  // Finishes the current step, joins and closes the run log.
  void Stop();

  // GL_RENDERER of the context (valid after Start).
  const std::string& renderer_name() const { return renderer_name_; }
  // True once the simulation loop stopped on an exception (docs/architecture.md,
  // "Failures"): it logged the error and sent the daemon SIGTERM.
  bool failed() const { return failed_; }

 private:
  void Run();
  void RunLockstep();
  void RunRealtime();
  void Fail(const char* what);
  void ApplyCommands();
  void Subscribe(session::ClientId client, session::SubscribeCommand& subscribe);
  void ApplyControls(session::ClientId client, session::ControlsCommand& controls);
  // Records a tracker's box (the servo of a kTrack UAV steers by it), or
  // answers the client an Error saying why not.
  void ApplyTrackerOutput(session::ClientId client, session::TrackerOutputCommand& output);
  void Configure(session::ClientId client, session::ConfigureCommand& command);
  // StartLog and StopLog (sim_thread_log.cpp): the sim thread owns the log.
  // `client` started it (with `link`), and unless StartLog.detach the log
  // ends when that client leaves (LogOwnerLeft).
  void ConfigureLog(session::ClientId client, const std::shared_ptr<session::ClientLink>& link,
                    const proto::Configure& request, proto::Configured& answer);
  // After a frame's record: a log that ended by itself (a failed write, a
  // cap) is dropped and the client that started it told why.
  void AfterLogAppend();
  // A client left: the log it started (without detach) is closed whole.
  void LogOwnerLeft(session::ClientId client);
  // The log is closed: forget it, so LoadMap, Reset and SetConditions are
  // allowed again and WorldInfo.log_file says "".
  void DropLog();
  // Tells the scheduler and the clients what `change` did; `world` is the
  // answer's WorldInfo. The graphics are already built for it.
  void AfterChange(const Simulation::Change& change, const proto::WorldInfo& world);
  // Whether the graphics must be rebuilt for the world after `change`: a
  // new scene, or a camera larger than the render targets.
  bool NeedsGraphics(const Simulation::Change& change) const;
  // Builds the meshes and renderer for the current scene and cameras; on a
  // throw the old ones stay (strong guarantee).
  void BuildGraphics();
  void AdvanceFrame();
  // Renders the channels `wanted` (ChannelsWanted) of one camera and hands
  // the frame to the scheduler.
  void RenderCamera(uint32_t camera_index, channels::ChannelSet wanted);
  void PublishState();
  void PublishWorld();

  const Config config_;
  session::CommandQueue& commands_;
  session::LatestState& latest_state_;
  session::WorldDirectory& directory_;
  session::Counters& counters_;
  // Pools first: frames handed out must be returned before the pools go.
  session::FramePool frame_pool_{4};
  session::StatePool state_pool_{4};
  Simulation sim_;
  CarDrivers drivers_;                 // who drives which car with Controls; --controls-timeout-ms
  std::unique_ptr<RunLogger> logger_;  // --log's or StartLog's, else null; the scheduler's observer
  // Who started the StartLog log (0: --log's, or none), their link while
  // they are connected, and whether the log outlives them (StartLog.detach).
  session::ClientId log_owner_ = 0;
  std::shared_ptr<session::ClientLink> log_owner_link_;
  bool log_detached_ = false;
  std::unique_ptr<AuthoringWorker> authoring_;  // CheckMap, GenerateMap, SaveMap, OpenMap, ListMaps; null once stopped
  session::Scheduler scheduler_;
  std::vector<session::Command> drained_;
  // Commands drained but not yet applied: once a frame's Configures have
  // taken limits::kConfigureBudgetPerFrameMs, the rest (and everything after
  // them, so order is kept) wait for the next round, after a frame.
  std::vector<session::Command> carried_;
  std::unique_ptr<render::GlContext> gl_;
  FrameAssembler frames_;
  std::string renderer_name_;
  std::atomic<bool> running_{false};
  std::atomic<bool> failed_{false};
  std::thread thread_;
};

}  // namespace sim4cv::daemon
