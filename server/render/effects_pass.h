// The camera effects (protocol/effects.h) as one post pass over the scene's
// render targets: lens distortion remaps every channel asked for alike (GT
// by nearest pixel, so ids and depths stay exact values; RGB bilinear; flow
// re-expressed in distorted pixels), and the RGB gets anti-aliasing, motion
// blur along the flow, exposure and white balance. One GLSL program per set
// of planes and effects, built the first time it is needed. Needs a current
// GL context; owns its program, lens maps and render targets.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "server/render/channel_program.h"
#include "server/render/lens.h"

namespace sim4cv::render {

class EffectsPass {
 public:
  EffectsPass(uint32_t max_width, uint32_t max_height);
  ~EffectsPass();
  EffectsPass(const EffectsPass&) = delete;
  EffectsPass& operator=(const EffectsPass&) = delete;

  // How much wider than `view` the scene must be drawn for its lens (1
  // without one: LensMap::widening); makes that lens map current.
  float Prepare(const CameraView& view);
  // The planes that must go through the pass for `view` with `planes` asked:
  // all with a lens, else RGB if an effect changes it.
  static PlaneSet Through(const CameraView& view, PlaneSet planes);
  // The scene planes the pass reads besides those: flow for motion blur.
  static PlaneSet Inputs(const CameraView& view, PlaneSet through);

  // Draws planes `through` of `view`'s image into this pass's framebuffer,
  // left bound: RGB from `scene` (texture i holds plane i, at the camera's
  // resolution), every other plane from `truth`, drawn `truth_scale` times
  // as fine (2 with a lens, else 1 and the same textures).
  using Textures = std::array<GLuint, channels::kPixelChannelCount>;
  void Draw(const CameraView& view, const Textures& scene, const Textures& truth, uint32_t truth_scale,
            PlaneSet through);
  GLuint framebuffer() const { return framebuffer_; }

 private:
  struct Program;
  struct Lens {
    CameraView key;  // size, field of view and coefficients it was made for
    LensMap map;
    GLuint texture = 0;
  };
  const Program& ProgramFor(PlaneSet through, uint32_t variant);

  uint32_t max_width_, max_height_;
  GLuint framebuffer_ = 0;
  std::array<GLuint, channels::kPixelChannelCount> targets_{};
  std::vector<Lens> lenses_;  // the last few lenses' maps; lenses_[current_] is in use
  std::size_t current_ = 0;
  std::vector<std::unique_ptr<Program>> programs_;  // index: planes + (1 << kPixelChannelCount) * variant
};

}  // namespace sim4cv::render
