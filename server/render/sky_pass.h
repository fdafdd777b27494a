// Draws the sky (gradient, sun disc, clouds, fog; shading.h) into the RGB
// target wherever the scene left the far plane, after the scene pass, so
// its fragment cost is paid only for sky pixels and no other channel changes.
// Needs a current GL context; owns its program.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Core>

#include "server/render/look_uniforms.h"

namespace sim4cv::render {

class SkyPass {
 public:
  SkyPass();
  ~SkyPass();
  SkyPass(const SkyPass&) = delete;
  SkyPass& operator=(const SkyPass&) = delete;

  // Draws into colour attachment `rgb_attachment` of the bound framebuffer,
  // whose depth buffer holds the scene. clip_from_world: the scene's
  // projection times view. Leaves the draw buffers set to that attachment alone.
  void Draw(GLuint rgb_attachment, const Eigen::Matrix4f& clip_from_world, const Eigen::Vector3f& camera_position,
            const Look& look, uint32_t noise_seed) const;

 private:
  GLuint program_ = 0;
  GLint u_world_from_clip_ = -1;
  LookUniforms look_;
};

}  // namespace sim4cv::render
