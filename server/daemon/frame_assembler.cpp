#include "server/daemon/frame_assembler.h"

#include <time.h>

#include <algorithm>
#include <cstring>

#include "server/daemon/state_message.h"
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

}  // namespace

FrameAssembler::FrameAssembler() = default;
FrameAssembler::~FrameAssembler() = default;

void FrameAssembler::Build(const sim::Scene& scene, const std::vector<sim::CameraSpec>& cameras) {
  // A new scene (or a camera larger than any before) needs new meshes or
  // larger render targets; the old ones die first, with the context current.
  uint32_t width = 1, height = 1;
  for (const auto& camera : cameras) {
    width = std::max(width, camera.width);
    height = std::max(height, camera.height);
  }
  auto graphics = std::make_unique<render::SceneGraphics>(scene);
  auto renderer = std::make_unique<render::Renderer>(graphics->meshes(), width, height);
  renderer->SetLook(look_);
  renderer->SetLamps(graphics->lamps());
  std::vector<uint32_t> unoccluded(graphics->instance_id_bound(), 0);
  // Nothing below throws; the old renderer dies before the meshes it drew.
  renderer_ = std::move(renderer);
  graphics_ = std::move(graphics);
  width_ = width;
  height_ = height;
  unoccluded_pixels_ = std::move(unoccluded);
  previous_views_.Clear();  // no flow across worlds
}

void FrameAssembler::SetLook(const render::Look& look) {
  look_ = look;
  if (renderer_) renderer_->SetLook(look_);
}

bool FrameAssembler::Fits(const std::vector<sim::CameraSpec>& cameras) const {
  return std::all_of(cameras.begin(), cameras.end(),
                     [&](const sim::CameraSpec& c) { return c.width <= width_ && c.height <= height_; });
}

void FrameAssembler::Release() {
  renderer_.reset();
  graphics_.reset();
}

void FrameAssembler::Update(const sim::State& state) {
  graphics_->Update(state);
  renderer_->SetHeadlights(graphics_->headlights());
}

void FrameAssembler::RememberViews(const std::vector<sim::CameraSpec>& cameras, const sim::State& state) {
  for (uint32_t camera = 0; camera < cameras.size(); ++camera) {
    previous_views_.Remember(camera, cameras[camera], graphics_->CameraAt(cameras[camera], state));
  }
}

render::FrameBuffers FrameAssembler::Targets(uint32_t index, const sim::CameraSpec& spec, channels::ChannelSet wanted,
                                             const session::Scheduler& scheduler, session::Frame& frame,
                                             session::PixelTargets& in_place, channels::ChannelSet& others) const {
  others = wanted;
  bool prepared = false;
  scheduler.ForEachLink(index, [&](session::ClientLink& link) {
    if (!prepared && link.PrepareTargets(index, spec.width, spec.height, in_place)) {
      prepared = true;
      others = scheduler.ChannelsSentFromFrame(index, &link);
    }
  });
  render::FrameBuffers buffers{};
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    const proto::Channel channel = channels::kPixelChannels[i].id;
    if (!channels::Has(wanted, channel)) continue;
    buffers[i] = in_place[i] != nullptr ? in_place[i] : frame.Hold(channel).data();
  }
  return buffers;
}

void FrameAssembler::Assemble(uint32_t index, const sim::CameraSpec& spec, const sim::State& state,
                              channels::ChannelSet wanted, const session::Scheduler& scheduler, session::Frame& frame) {
  // The boxes are extracted from the instance mask.
  const bool boxes = channels::Has(wanted, proto::CHANNEL_BOXES);
  if (boxes) wanted |= channels::Bit(proto::CHANNEL_MASK);
  frame.frame_id = state.frame_id;
  frame.sim_time = state.sim_time;
  frame.camera_index = index;
  frame.camera_name = spec.name;
  frame.width = spec.width;
  frame.height = spec.height;
  frame.channels = 0;
  session::PixelTargets in_place{};
  channels::ChannelSet others = 0;
  const render::FrameBuffers buffers = Targets(index, spec, wanted, scheduler, frame, in_place, others);

  auto& labelled = graphics_->labelled_objects();
  for (const auto& object : labelled) unoccluded_pixels_[object.instance] = 0;
  render::CameraView view = graphics_->CameraAt(spec, state);
  view.previous_world_from_camera = previous_views_.Of(index, spec, view);
  view.noise_seed = static_cast<uint32_t>(state.frame_id * 0x9E3779B1u + index);  // repeatable per frame and camera
  view.effects = effects_;
  renderer_->Render(view, graphics_->draw_items(), buffers,
                    boxes ? std::span<uint32_t>(unoccluded_pixels_) : std::span<uint32_t>());
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    const proto::Channel channel = channels::kPixelChannels[i].id;
    if (in_place[i] != nullptr && buffers[i] == in_place[i] && channels::Has(others, channel)) {
      const std::span<uint8_t> plane = frame.Hold(channel);  // another transport sends it too
      std::memcpy(plane.data(), in_place[i], plane.size());
    }
  }
  frame.boxes.clear();
  frame.objects.clear();
  const render::BoxProjector camera(view);
  frame.intrinsics = camera.intrinsics();
  frame.camera_pose = render::OpenCvPoseOf(view);
  if (boxes) {
    for (auto& object : labelled) object.unoccluded_pixels = unoccluded_pixels_[object.instance];
    const auto* mask = reinterpret_cast<const uint16_t*>(buffers[*channels::IndexOf(proto::CHANNEL_MASK)]);
    boxes_.Extract(mask, spec.width, spec.height, labelled, frame.boxes);
    // 3D ground truth from the very view that was rendered, so it matches the pixels.
    graphics_->catalog().Fill(graphics_->moving_objects(), camera, frame.boxes, frame.objects);
  }
  FillStateMessage(state, frame.state);
  frame.render_end_mono_ns = MonotonicNanoseconds();
}

}  // namespace sim4cv::daemon
