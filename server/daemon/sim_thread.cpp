#include "server/daemon/sim_thread.h"

#include <time.h>

#include <chrono>
#include <future>

#include "server/common/log.h"
#include "server/daemon/state_message.h"
#include "server/render/gl_context.h"
#include "server/render/projection.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"

namespace sim4cv::daemon {
namespace {

int64_t MonotonicNanoseconds() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

template <typename... Handlers>
struct Overloaded : Handlers... {
  using Handlers::operator()...;
};

}  // namespace

SimThread::SimThread(const Config& config, const sim::Scene& scene, session::CommandQueue& commands,
                     session::LatestState& latest_state, session::Counters& counters)
    : config_(config), scene_(scene), commands_(commands), latest_state_(latest_state), world_(scene),
      state_(world_.InitialState()) {
  if (!config.replay_file.empty()) world_.SetReplay(LoadReplayTrack(config, scene));
  if (!config.log_file.empty()) {
    logger_ = std::make_unique<RunLogger>(config, scene, counters);
    scheduler_.SetObserver(logger_.get());
  }
  PublishState();  // GetState before the first step sees frame 0
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
      gl_ = render::CreateOsMesaContext();
      gl_->MakeCurrent();
      renderer_name_ = gl_->RendererName();
      graphics_ = std::make_unique<render::SceneGraphics>(scene_);
      uint32_t max_width = 1, max_height = 1;
      for (const auto& camera : scene_.cameras) {
        max_width = std::max(max_width, camera.width);
        max_height = std::max(max_height, camera.height);
      }
      renderer_ = std::make_unique<render::Renderer>(graphics_->meshes(), max_width, max_height);
      unoccluded_pixels_.assign(graphics_->instance_id_bound(), 0);
      ready.set_value();
    } catch (...) {
      ready.set_exception(std::current_exception());
      return;
    }
    Run();
    // GL objects die on the thread whose context is current.
    renderer_.reset();
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

void SimThread::Stop() {
  running_ = false;
  commands_.Wake();
  if (thread_.joinable()) thread_.join();
  if (logger_) logger_->Close();
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
    // Only a wake-up source: lockstep results never depend on wall time.
    commands_.WaitUntil(std::chrono::steady_clock::now() + std::chrono::milliseconds(200));
  }
}

void SimThread::RunRealtime() {
  using Clock = std::chrono::steady_clock;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.frame_hz));
  auto next_frame = Clock::now() + period;
  while (running_) {
    commands_.WaitUntil(next_frame);
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

void SimThread::ApplyCommands() {
  commands_.Drain(drained_);
  for (auto& command : drained_) {
    const session::ClientId client = command.client;
    std::visit(Overloaded{
                   [&](session::SubscribeCommand& c) {
                     scheduler_.Subscribe(client, c.camera_index, c.delivery, std::move(c.link));
                   },
                   [&](session::StepCommand&) { scheduler_.AddStep(client); },
                   [&](session::ControlsCommand& c) {
                     state_.car_command = {c.steering, c.throttle, c.brake, true};
                   },
                   [&](session::TrackerOutputCommand& c) {
                     sim::TrackerReport report{client, c.frame_id, c.x, c.y, c.width, c.height, c.confidence};
                     auto& reports = state_.tracker_reports;
                     auto it = std::lower_bound(reports.begin(), reports.end(), client,
                                                [](const sim::TrackerReport& r, uint32_t id) { return r.client_id < id; });
                     if (it != reports.end() && it->client_id == client) {
                       *it = report;
                     } else {
                       reports.insert(it, report);
                     }
                   },
                   [&](session::DisconnectCommand&) { scheduler_.Remove(client); },
               },
               command.body);
  }
  drained_.clear();  // drop links held by commands before waiting again
}

void SimThread::AdvanceFrame() {
  const double dt = 1.0 / config_.physics_hz;
  for (uint32_t i = 0; i < config_.substeps_per_frame(); ++i) world_.Step(state_, dt);
  ++state_.frame_id;
  PublishState();
  for (uint32_t camera = 0; camera < scene_.cameras.size(); ++camera) {
    if (scheduler_.CameraWanted(camera)) RenderCamera(camera);
  }
  if (logger_) {
    logger_->Append(state_, scheduler_);
    scheduler_.ReleaseFrames();  // only now, with the record written, may clients see the frames
  }
}

void SimThread::RenderCamera(uint32_t camera_index) {
  session::Frame* frame = nullptr;
  session::FrameRef ref = frame_pool_.Acquire(&frame);
  const auto& spec = scene_.cameras[camera_index];
  const std::size_t pixels = static_cast<std::size_t>(spec.width) * spec.height;
  // Pooled frames keep their buffers, so these resizes allocate only at start.
  frame->rgb.resize(pixels * 3);
  frame->depth.resize(pixels);
  frame->mask.resize(pixels);
  frame->frame_id = state_.frame_id;
  frame->sim_time = state_.sim_time;
  frame->camera_index = camera_index;
  frame->width = spec.width;
  frame->height = spec.height;

  auto& labelled = graphics_->labelled_objects();
  for (const auto& object : labelled) unoccluded_pixels_[object.instance] = 0;
  const render::CameraView view = graphics_->CameraAt(camera_index, state_);
  renderer_->Render(view, graphics_->DrawItems(state_), {frame->rgb.data(), frame->depth.data(), frame->mask.data()},
                    unoccluded_pixels_);
  for (auto& object : labelled) object.unoccluded_pixels = unoccluded_pixels_[object.instance];
  boxes_.Extract(frame->mask.data(), spec.width, spec.height, labelled, frame->boxes);
  // 3D ground truth from the very view that was rendered, so it matches the pixels.
  const render::BoxProjector camera(view);
  frame->intrinsics = camera.intrinsics();
  frame->camera_pose = render::OpenCvPoseOf(view);
  graphics_->catalog().Fill(state_, camera, frame->boxes, frame->objects);
  FillStateMessage(scene_, state_, frame->state);
  frame->render_end_mono_ns = MonotonicNanoseconds();
  scheduler_.Deliver(ref);
}

void SimThread::PublishState() {
  session::StateSnapshot* snapshot = nullptr;
  session::StateRef ref = state_pool_.Acquire(&snapshot);
  FillStateMessage(scene_, state_, snapshot->state);
  snapshot->tracker_clients.clear();
  snapshot->tracker_outputs.resize(state_.tracker_reports.size());
  for (std::size_t i = 0; i < state_.tracker_reports.size(); ++i) {
    const sim::TrackerReport& r = state_.tracker_reports[i];
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
