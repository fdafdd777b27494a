#include "server/daemon/sim_thread.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <future>

#include "server/common/diagnostics.h"
#include "server/common/limits.h"
#include "server/daemon/state_message.h"
#include "server/daemon/tracker_reports.h"
#include "server/render/gl_context.h"
#include "server/render/look.h"
#include "server/session/client_protocol.h"

namespace sim4cv::daemon {
namespace {

// Answers a client the sim thread refuses something to (nothing if it has
// no link), phrased as every other non-fatal Error.
void OfferError(session::ClientLink* link, proto::ErrorCode code, const std::string& message) {
  if (!link) return;
  proto::Envelope reply;
  session::ClientProtocol::Refuse(code, message, false, reply);
  link->OfferReply(std::move(reply));
}

template <typename... Handlers>
struct Overloaded : Handlers... {
  using Handlers::operator()...;
};

}  // namespace

SimThread::SimThread(const Config& config, std::shared_ptr<const sim::Scene> scene, session::CommandQueue& commands,
                     session::LatestState& latest_state, session::WorldDirectory& directory,
                     session::Counters& counters)
    : config_(config),
      commands_(commands),
      latest_state_(latest_state),
      directory_(directory),
      counters_(counters),
      sim_(config_, std::move(scene)),
      drivers_(config_.controls_timeout_ms) {
  const sim::Scene& scene_ref = sim_.scene();
  if (!config.log_file.empty()) {
    logger_ = std::make_unique<RunLogger>(config, scene_ref, sim_.state(), counters);
    scheduler_.SetObserver(logger_.get());
  }
  PublishState();  // GetState before the first step sees frame 0
  PublishWorld();
  authoring_ = std::make_unique<AuthoringWorker>(config_, directory_);
}

SimThread::~SimThread() {
  Stop();
  latest_state_.Publish({});  // its snapshot belongs to our pool
}

void SimThread::Start() {
  std::promise<void> ready;
  auto ready_future = ready.get_future();
  running_ = true;
  thread_ = std::thread([this, &ready] {
    try {
      // OSMesa contexts are current per thread, so everything GL is made here.
      gl_ = render::CreateGlContext();
      gl_->MakeCurrent();
      renderer_name_ = gl_->RendererName();
      BuildGraphics();
      ready.set_value();
    } catch (...) {
      ready.set_exception(std::current_exception());
      return;
    }
    try {
      Run();
    } catch (const std::exception& error) {
      Fail(error.what());
    } catch (...) {
      Fail("an exception of unknown type");
    }
    // GL objects die on the thread whose context is current.
    frames_.Release();
    gl_.reset();
  });
  try {
    ready_future.get();
  } catch (...) {
    running_ = false;
    thread_.join();
    throw;
  }
}

// A frame could not be simulated, rendered or logged (what Configure throws
// never gets here): the world may be half-stepped, so no frame after it can
// be trusted. The daemon stops as on SIGTERM, closing the run log, and exits
// with status 1 (docs/architecture.md, "Failures").
void SimThread::Fail(const char* what) {
  LOG_ERROR("the simulation stopped at frame " << sim_.state().frame_id << ": " << what
                                               << "; sim4cvd shuts down (exit status 1)");
  failed_ = true;
  running_ = false;
  kill(getpid(), SIGTERM);  // to the process: the main thread's sigwait takes it
}

void SimThread::Stop() {
  running_ = false;
  commands_.Wake();
  if (thread_.joinable()) thread_.join();
  authoring_.reset();  // it holds client links too
  if (logger_) logger_->Close();
  // Let go of every client link (subscriptions, commands still queued): the
  // sessions behind them must die with their transports, whose I/O objects
  // cannot outlive the transport's io_context (found by the ASan build).
  scheduler_.DropCamerasFrom(0);
  commands_.Drain(drained_);
  drained_.clear();
  carried_.clear();
}

void SimThread::Run() {
  if (config_.mode == proto::SIM_MODE_LOCKSTEP) {
    RunLockstep();
  } else {
    RunRealtime();
  }
}

void SimThread::RunLockstep() {
  while (running_) {
    ApplyCommands();
    if (scheduler_.LockstepReady()) {
      scheduler_.ConsumeSteps();
      AdvanceFrame();
      continue;
    }
    if (!carried_.empty()) continue;  // commands over the last round's budget
    // Only a wake-up source: lockstep results never depend on wall time.
    commands_.WaitUntil(std::chrono::steady_clock::now() + std::chrono::milliseconds(200));
  }
}

void SimThread::RunRealtime() {
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.frame_hz));
  auto next_frame = Clock::now() + period;
  while (running_) {
    if (carried_.empty()) commands_.WaitUntil(next_frame);
    ApplyCommands();
    const auto now = Clock::now();
    if (now < next_frame) continue;
    AdvanceFrame();
    next_frame += period;
    if (now - next_frame > std::chrono::seconds(1)) {
      LOG_WARNING("simulation fell more than 1 s behind wall time; skipping ahead");
      next_frame = now + period;
    }
  }
}

void SimThread::BuildGraphics() {
  frames_.SetLook(render::LookOf(sim_.conditions()));
  frames_.SetEffects(sim_.effects());
  frames_.Build(sim_.scene(), sim_.cameras());
}

bool SimThread::NeedsGraphics(const Simulation::Change& change) const {
  return change.new_scene || !frames_.Fits(sim_.cameras());
}

void SimThread::ApplyCommands() {
  // A burst's frames go back to the system (at most once a period; ref_pool.h).
  frame_pool_.Trim(limits::kFramePoolSpare, std::chrono::milliseconds(limits::kFramePoolTrimPeriodMs));
  commands_.Drain(drained_);
  // Commands left over from the last round come first: the order is kept.
  std::vector<session::Command>& pending = carried_.empty() ? drained_ : carried_;
  if (!carried_.empty()) std::move(drained_.begin(), drained_.end(), std::back_inserter(carried_));
  const auto start = std::chrono::steady_clock::now();
  const auto budget = std::chrono::milliseconds(limits::kConfigureBudgetPerFrameMs);
  std::size_t applied = 0;
  for (; applied < pending.size(); ++applied) {
    session::Command& command = pending[applied];
    const session::ClientId client = command.client;
    if (std::holds_alternative<session::ConfigureCommand>(command.body) &&
        std::chrono::steady_clock::now() - start > budget) {
      break;  // the rest after a frame
    }
    std::visit(Overloaded{
                   [&](session::SubscribeCommand& c) { Subscribe(client, c); },
                   [&](session::StepCommand&) { scheduler_.AddStep(client); },
                   [&](session::ControlsCommand& c) { ApplyControls(client, c); },
                   [&](session::TrackerOutputCommand& c) { ApplyTrackerOutput(client, c); },
                   [&](session::ConfigureCommand& c) { Configure(client, c); },
                   [&](session::DisconnectCommand&) {
                     scheduler_.Remove(client);
                     drivers_.Release(client);
                     ForgetTrackerReport(sim_.state(), client);
                     LogOwnerLeft(client);
                   },
               },
               command.body);
  }
  if (applied < pending.size()) counters_.Add("configure.deferred");
  if (&pending == &drained_) {
    std::move(drained_.begin() + static_cast<std::ptrdiff_t>(applied), drained_.end(), std::back_inserter(carried_));
  } else {
    carried_.erase(carried_.begin(), carried_.begin() + static_cast<std::ptrdiff_t>(applied));
  }
  drained_.clear();  // drop links held by commands before waiting again
}

void SimThread::Subscribe(session::ClientId client, session::SubscribeCommand& subscribe) {
  const auto& cameras = sim_.cameras();
  if (subscribe.camera_index < cameras.size() && !cameras[subscribe.camera_index].name.empty()) {
    scheduler_.Subscribe(client, subscribe.camera_index, subscribe.delivery, subscribe.channels,
                         std::move(subscribe.link), subscribe.gate, subscribe.min_interval_ns);
    return;
  }
  // The camera went (RemoveCamera, Remove, Reset, LoadMap) between the
  // network thread's check and now.
  OfferError(subscribe.link.get(), proto::ERROR_CODE_UNKNOWN_CAMERA,
             "the camera you subscribed to was removed before the subscription took effect; "
             "subscribe to a camera the world has (GetWorld lists them)");
}

void SimThread::ApplyControls(session::ClientId client, session::ControlsCommand& controls) {
  sim::State& state = sim_.state();
  sim::Entity* car = state.Find(controls.entity_id);
  if (!car || car->kind != sim::EntityKind::kCar) {
    OfferError(controls.link.get(), proto::ERROR_CODE_UNKNOWN_ENTITY,
               "Controls.entity_id " + std::to_string(controls.entity_id) + " is not a car; the world holds " +
                   sim::EntityList(state));
    return;
  }
  // One driver per car: another client's Controls are refused, not mixed in.
  const std::string refused = drivers_.Drive(state, *car, client, controls);
  if (!refused.empty()) OfferError(controls.link.get(), proto::ERROR_CODE_INVALID_STATE, refused);
}

void SimThread::ApplyTrackerOutput(session::ClientId client, session::TrackerOutputCommand& output) {
  std::optional<ReportCamera> camera;
  if (const auto index = scheduler_.CameraOf(client); index && *index < sim_.cameras().size()) {
    const sim::CameraSpec& spec = sim_.cameras()[*index];
    const sim::Entity* mount = spec.mounted_on.empty() ? nullptr : sim_.state().FindByName(spec.mounted_on);
    camera = ReportCamera{spec.name, mount ? mount->id : 0, spec.width, spec.height};
  }
  const std::string problem = RecordTrackerReport(sim_.state(), client, output, camera ? &*camera : nullptr);
  if (!problem.empty()) OfferError(output.link.get(), proto::ERROR_CODE_INVALID_ARGUMENT, problem);
}

// Any exception out of carrying out a request becomes that client's Error,
// and the world stays as it was: Simulation::Apply changes nothing when it
// throws, and the graphics a change needs are built before the change is
// committed (Undo() otherwise), so what is rendered always matches the world.
void SimThread::Configure(session::ClientId client, session::ConfigureCommand& command) {
  proto::Envelope reply;
  const uint64_t request_id = command.request.request_id();
  const auto refuse = [&](proto::ErrorCode code, const std::string& message) {
    reply.Clear();
    session::ClientProtocol::Refuse(code, message, false, reply);
    reply.mutable_error()->set_request_id(request_id);
  };
  try {
    proto::Configured& answer = *reply.mutable_configured();
    if (AuthoringWorker::Handles(command.request)) {
      authoring_->Post(std::move(command));  // it answers; the world does not wait
      return;
    }
    if (command.request.has_start_log() || command.request.has_stop_log()) {
      answer.set_request_id(command.request.request_id());
      ConfigureLog(client, command.link, command.request, answer);
      directory_.Publish(answer.world());  // its log_file, as later answers see it
      if (command.link) command.link->OfferReply(std::move(reply));
      return;
    }
    const Simulation::Change change = sim_.Apply(command.request, answer);
    try {
      if (NeedsGraphics(change)) BuildGraphics();
    } catch (...) {
      sim_.Undo();
      throw;
    }
    sim_.Commit();
    drivers_.AfterConfigure(sim_.state(), change.new_scene);  // only now: an Undo keeps the drivers
    if (change.new_conditions) {
      frames_.SetLook(render::LookOf(sim_.conditions()));
      LOG_INFO("conditions now " << conditions::Describe(sim_.conditions()));
    }
    if (change.new_effects) {
      frames_.SetEffects(sim_.effects());
      LOG_INFO("camera effects now " << effects::Describe(sim_.effects()));
    }
    AfterChange(change, answer.world());  // only now does the answer hold the world
  } catch (const ConfigureError& refused) {
    refuse(refused.code(), refused.what());
    LOG_INFO("Configure " << request_id << " refused: " << refused.what());
  } catch (const std::exception& failed) {
    // Out of memory building a map's world or meshes, or a value the
    // checks let through that the world cannot hold: not this client's
    // fault alone, so the operator hears of it too.
    const std::string what = failed.what();
    refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
           "the daemon could not carry out this Configure (" + what +
               "); the world is as it was before it. A smaller map, camera or request may fit (docs/maps.md, "
               "\"Limits\")");
    LOG_WARNING("Configure " << request_id << " failed, world unchanged: " << what);
  } catch (...) {
    refuse(proto::ERROR_CODE_INVALID_ARGUMENT,
           "the daemon could not carry out this Configure (an exception of unknown type); the world is as it was "
           "before it");
    LOG_WARNING("Configure " << request_id << " failed with an exception of unknown type, world unchanged");
  }
  if (command.link) command.link->OfferReply(std::move(reply));
}

void SimThread::AfterChange(const Simulation::Change& change, const proto::WorldInfo& world) {
  const auto tell = [](const std::vector<std::shared_ptr<session::ClientLink>>& links, const std::string& message) {
    for (const auto& link : links) OfferError(link.get(), proto::ERROR_CODE_UNKNOWN_CAMERA, message);
  };
  if (change.new_scene) {
    const auto scene_cameras = static_cast<uint32_t>(sim_.scene().cameras.size());
    tell(scheduler_.DropCamerasFrom(scene_cameras),
         "the camera you subscribed to was removed: the world was reset or a map loaded; subscribe again");
    for (uint32_t i = 0; i < scene_cameras; ++i) scheduler_.SetCameraDead(i, false);
    PublishState();
  }
  for (const uint32_t camera : change.removed_cameras) {
    tell(scheduler_.SetCameraDead(camera, true),
         "the camera you subscribed to was removed (it, or the entity it rode, is gone); it sends no more frames");
  }
  // The answer already holds the world after the change: publish a copy.
  if (change.world_changed) directory_.Publish(world);
}

void SimThread::PublishWorld() {
  proto::WorldInfo world;
  sim_.FillWorldInfo(world);
  directory_.Publish(std::move(world));
}

void SimThread::AdvanceFrame() {
  const double dt = 1.0 / config_.physics_hz;
  sim::State& state = sim_.state();
  // Once per frame, before its physics: a car whose driver went quiet stops.
  if (const uint32_t stopped = drivers_.BrakeStale(state); stopped > 0) counters_.Add("controls.timeouts", stopped);
  for (uint32_t i = 0; i < config_.substeps_per_frame(); ++i) sim_.world().Step(state, dt);
  ++state.frame_id;
  if (sim_.AdvanceConditions()) frames_.SetLook(render::LookOf(sim_.conditions()));
  PublishState();
  frames_.Update(state);
  const auto& cameras = sim_.cameras();
  scheduler_.BeginFrame(std::chrono::steady_clock::now());  // for Subscribe.max_fps
  for (uint32_t camera = 0; camera < cameras.size(); ++camera) {
    const channels::ChannelSet wanted = scheduler_.ChannelsWanted(camera);
    if (wanted != 0) RenderCamera(camera, wanted);
  }
  frames_.RememberViews(cameras, state);
  if (logger_) {
    logger_->Append(state, scheduler_);
    scheduler_.ReleaseFrames();  // only now, with the record written, may clients see the frames
    AfterLogAppend();
  }
}

void SimThread::RenderCamera(uint32_t camera_index, channels::ChannelSet wanted) {
  session::Frame* frame = nullptr;
  session::FrameRef ref = frame_pool_.Acquire(&frame);
  frames_.Assemble(camera_index, sim_.cameras()[camera_index], sim_.state(), wanted, scheduler_, *frame);
  scheduler_.Deliver(ref);
}

void SimThread::PublishState() {
  session::StateSnapshot* snapshot = nullptr;
  session::StateRef ref = state_pool_.Acquire(&snapshot);
  const sim::State& state = sim_.state();
  FillStateMessage(state, snapshot->state);
  snapshot->tracker_clients.clear();
  snapshot->tracker_outputs.resize(state.tracker_reports.size());
  for (std::size_t i = 0; i < state.tracker_reports.size(); ++i) {
    const sim::TrackerReport& r = state.tracker_reports[i];
    snapshot->tracker_clients.push_back(r.client_id);
    proto::TrackerOutput& out = snapshot->tracker_outputs[i];
    out.set_frame_id(r.frame_id);
    out.mutable_box()->set_x(r.x);
    out.mutable_box()->set_y(r.y);
    out.mutable_box()->set_width(r.width);
    out.mutable_box()->set_height(r.height);
    out.set_confidence(r.confidence);
  }
  latest_state_.Publish(std::move(ref));
}

}  // namespace sim4cv::daemon
