#include "server/render/render_targets.h"

#include "server/common/check.h"

namespace sim4cv::render {
namespace {

constexpr std::size_t kRgbPlane = *channels::IndexOf(proto::CHANNEL_RGB);

}  // namespace

RenderTargets::RenderTargets(uint32_t width, uint32_t height) : width_(width), height_(height) {
  glGenFramebuffers(1, &framebuffer_);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glGenRenderbuffers(1, &depth_stencil_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_stencil_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, static_cast<GLsizei>(width),
                        static_cast<GLsizei>(height));
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, depth_stencil_);
}

RenderTargets::~RenderTargets() {
  glDeleteTextures(static_cast<GLsizei>(textures_.size()), textures_.data());
  glDeleteRenderbuffers(1, &depth_stencil_);
  glDeleteFramebuffers(1, &framebuffer_);
}

void RenderTargets::Bind(PlaneSet planes) {
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  std::array<GLenum, channels::kPixelChannelCount> draw_buffers{};
  for (GLuint i = 0; i < channels::kPixelChannelCount; ++i) {
    draw_buffers[i] = GL_NONE;
    if ((planes & (1u << i)) == 0) continue;
    if (textures_[i] == 0) {
      glGenTextures(1, &textures_[i]);
      glBindTexture(GL_TEXTURE_2D, textures_[i]);
      glTexStorage2D(GL_TEXTURE_2D, 1, kChannelOutputs[i]->target_format, static_cast<GLsizei>(width_),
                     static_cast<GLsizei>(height_));
      // RGB is resampled between pixels by a lens; the rest are looked up exactly.
      const GLint filter = i == kRgbPlane ? GL_LINEAR : GL_NEAREST;
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, filter);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, filter);
      glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, textures_[i], 0);
    }
    draw_buffers[i] = GL_COLOR_ATTACHMENT0 + i;
  }
  glDrawBuffers(static_cast<GLsizei>(draw_buffers.size()), draw_buffers.data());
  SIM4CV_THROW_UNLESS(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                      "renderer framebuffer is incomplete");
}

}  // namespace sim4cv::render
