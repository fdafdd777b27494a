// The world the render tests of the look and the camera effects draw: the
// densest urban map with traffic, stepped two seconds, its graphics and one
// renderer, made once per test suite. A shot renders every channel of one
// camera that slid 0.3 m since its previous frame, so flow is not zero.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <vector>

#include "server/render/gl_context.h"
#include "server/render/renderer.h"
#include "server/render/scene_graphics.h"
#include "server/sim/world.h"
#include "tests/support/rendered_frame.h"
#include "tests/unit/traffic_test_support.h"

namespace sim4cv::testing {

using render::CameraView;
using render::Renderer;

class UrbanRenderTest : public ::testing::Test {
 protected:
  static constexpr uint32_t kWidth = 240, kHeight = 135;

  static void SetUpTestSuite() {
    scene_ = std::make_unique<sim::Scene>(sim::SceneFromMap(
        (traffic::testing::SourceDir() / "scenes/driving/train/01_urban.map").string(), "", 8.0f, kWidth, kHeight));
    sim::AddTraffic(*scene_, traffic::testing::Config(10, 12, 12));
    world_ = std::make_unique<sim::World>(*scene_);
    state_ = std::make_unique<sim::State>(world_->InitialState());
    for (int i = 0; i < 480; ++i) world_->Step(*state_, 1.0 / 240.0);
    context_ = render::CreateGlContext();
    graphics_ = std::make_unique<render::SceneGraphics>(*scene_);
    graphics_->Update(*state_);
    renderer_ = std::make_unique<Renderer>(graphics_->meshes(), kWidth, kHeight);
  }
  static void TearDownTestSuite() {
    renderer_.reset();
    graphics_.reset();
    context_.reset();
    state_.reset();
    world_.reset();
    scene_.reset();
  }

  struct Shot {
    RenderedFrame frame{kWidth, kHeight};
    std::vector<uint32_t> unoccluded;
  };

  // Camera `index` as the shots see it.
  static CameraView View(std::size_t index) {
    CameraView view = graphics_->CameraAt(scene_->cameras[index], *state_);
    view.previous_world_from_camera = view.world_from_camera;
    view.previous_world_from_camera(0, 3) -= 0.3f;
    return view;
  }
  // Every channel of `view`, with the unoccluded counts, by `renderer`.
  static Shot Render(const CameraView& view, Renderer& renderer) {
    Shot shot;
    shot.unoccluded.assign(graphics_->instance_id_bound(), 0);
    renderer.Render(view, graphics_->draw_items(), shot.frame.Buffers(channels::kAllPixels), shot.unoccluded);
    return shot;
  }
  static Shot Render(const CameraView& view) { return Render(view, *renderer_); }

  inline static std::unique_ptr<sim::Scene> scene_;
  inline static std::unique_ptr<sim::World> world_;
  inline static std::unique_ptr<sim::State> state_;
  inline static std::unique_ptr<render::GlContext> context_;
  inline static std::unique_ptr<render::SceneGraphics> graphics_;
  inline static std::unique_ptr<Renderer> renderer_;
};

template <typename T>
bool SameBytes(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

}  // namespace sim4cv::testing
