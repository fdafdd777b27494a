// A depth map of the scene seen from the sun, for the RGB channel's shadows.
// One orthographic map fitted to the ground the camera looks at, moved in
// whole texels so shadow edges do not crawl as the camera moves.
// Needs a current GL context; owns its texture, framebuffer and program.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Core>

#include "server/render/look_uniforms.h"
#include "server/render/render_types.h"

namespace sim4cv::render {

class ShadowMap {
 public:
  // size: texels on a side; radius_m: half the side of the square of ground covered.
  ShadowMap(GLsizei size, float radius_m);
  ~ShadowMap();
  ShadowMap(const ShadowMap&) = delete;
  ShadowMap& operator=(const ShadowMap&) = delete;

  // The sun's clip_from_world for `camera`: a square around the ground the
  // camera looks at, snapped to whole texels.
  Eigen::Matrix4f Fit(const CameraView& camera, const Eigen::Vector3f& to_sun) const;

  // Binds the map's framebuffer and depth-only program and clears it; the
  // caller draws the casters with ModelLocation() set per item, then End().
  void Begin(const Eigen::Matrix4f& clip_from_world) const;
  GLint ModelLocation() const { return u_model_; }
  // How the RGB pass samples what was drawn.
  ShadowSampling End(const Eigen::Matrix4f& clip_from_world) const;

 private:
  GLsizei size_;
  float radius_m_;
  GLuint texture_ = 0, framebuffer_ = 0, program_ = 0;
  GLint u_model_ = -1, u_clip_from_world_ = -1;
};

}  // namespace sim4cv::render
