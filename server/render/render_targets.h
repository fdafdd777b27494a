// One framebuffer with a texture per pixel channel (plane i at colour
// attachment i, made the first time it is drawn, readable by the effects
// pass) and a depth-stencil buffer. The renderer has one at the largest
// camera size, and with a lens a second at twice that for the ground truth.
// Needs a current GL context; owns its GL objects.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <cstdint>

#include "server/render/channel_program.h"

namespace sim4cv::render {

class RenderTargets {
 public:
  RenderTargets(uint32_t width, uint32_t height);
  ~RenderTargets();
  RenderTargets(const RenderTargets&) = delete;
  RenderTargets& operator=(const RenderTargets&) = delete;

  // Binds the framebuffer with `planes` as its draw buffers.
  void Bind(PlaneSet planes);
  GLuint framebuffer() const { return framebuffer_; }
  // Plane i's texture (0 until first drawn).
  const std::array<GLuint, channels::kPixelChannelCount>& textures() const { return textures_; }
  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }

 private:
  uint32_t width_, height_;
  GLuint framebuffer_ = 0, depth_stencil_ = 0;
  std::array<GLuint, channels::kPixelChannelCount> textures_{};
};

}  // namespace sim4cv::render
