// How the sim thread turns the world into camera frames: the scene's
// graphics and the renderer built for them, each camera's previous view (for
// optical flow), and per frame the pixels of the channels asked for plus the
// 2D and 3D ground truth of exactly the view that was rendered. Used only on
// the sim thread, with its GL context current.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include "protocol/channels.h"
#include "server/render/ground_truth.h"
#include "server/render/look.h"
#include "server/render/previous_views.h"
#include "server/session/frame.h"
#include "server/session/scheduler.h"
#include "server/sim/scene.h"
#include "server/sim/state.h"

namespace sim4cv::render {
class Renderer;
class SceneGraphics;
}  // namespace sim4cv::render

namespace sim4cv::daemon {

class FrameAssembler {
 public:
  FrameAssembler();
  ~FrameAssembler();
  FrameAssembler(const FrameAssembler&) = delete;
  FrameAssembler& operator=(const FrameAssembler&) = delete;

  // Builds the meshes and a renderer whose targets fit every camera; on a
  // throw the old ones stay (strong guarantee). Forgets the previous views.
  void Build(const sim::Scene& scene, const std::vector<sim::CameraSpec>& cameras);
  // How RGB is lit from now on, kept across Build (look.h).
  void SetLook(const render::Look& look);
  // What every camera does to the light from now on (protocol/effects.h).
  void SetEffects(const effects::CameraEffects& effects) { effects_ = effects; }
  // Whether the render targets are large enough for every camera.
  bool Fits(const std::vector<sim::CameraSpec>& cameras) const;
  // Frees the GL objects (while the context is still current).
  void Release();

  // Brings the graphics up to `state`, once per frame before Assemble.
  void Update(const sim::State& state);
  // Renders camera `index` (its channels `wanted`, ChannelsWanted) into
  // `frame` and fills its ground truth. A subscriber that takes pixels in
  // place (the shm ring, ClientLink::PrepareTargets) gets its channels read
  // back straight into its memory; they are copied into `frame` only if
  // another subscriber wants them too.
  void Assemble(uint32_t index, const sim::CameraSpec& spec, const sim::State& state, channels::ChannelSet wanted,
                const session::Scheduler& scheduler, session::Frame& frame);
  // Every camera's view at `state`, rendered or not: the next frame's flow starts there.
  void RememberViews(const std::vector<sim::CameraSpec>& cameras, const sim::State& state);

 private:
  // Where each wanted channel is rendered; fills `in_place` and `others`.
  render::FrameBuffers Targets(uint32_t index, const sim::CameraSpec& spec, channels::ChannelSet wanted,
                               const session::Scheduler& scheduler, session::Frame& frame,
                               session::PixelTargets& in_place, channels::ChannelSet& others) const;

  std::unique_ptr<render::SceneGraphics> graphics_;
  std::unique_ptr<render::Renderer> renderer_;
  render::Look look_;
  effects::CameraEffects effects_;
  render::BoxExtractor boxes_;
  render::PreviousViews previous_views_;
  std::vector<uint32_t> unoccluded_pixels_;
  uint32_t width_ = 0, height_ = 0;  // of the render targets
};

}  // namespace sim4cv::daemon
