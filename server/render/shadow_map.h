// A depth map of the scene seen from the sun, for the RGB channel's shadows.
// One orthographic map fitted to the ground the camera looks at, moved in
// steps of kSnapM so shadow edges do not crawl as the camera moves and the
// fixed casters' depth (most of the geometry) is drawn only when the map
// moves or the sun turns; each frame copies it and adds the moving casters.
// The fixed casters' depth is kept for the last kFixedEntries fits, so that
// several cameras (each with its own fit) each find theirs instead of
// redrawing the fixed casters every frame.
// Needs a current GL context; owns its textures, framebuffers and program.
#pragma once

#define GL_GLEXT_PROTOTYPES

#include <array>
#include <cstddef>
#include <cstdint>
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Core>

#include "server/render/look_uniforms.h"
#include "server/render/render_types.h"

namespace sim4cv::render {

// Whether a caster inside the sphere (centre, radius) can shadow anything inside the
// frustum `view_planes` (camera_math.h's FrustumPlanes) under the sun `to_sun` (unit,
// world). A caster darkens only what lies on the sun's rays through it beyond it: the
// sphere swept away from the sun down to below any ground. Where that capsule is
// wholly outside one plane of the view, no pixel of the view samples a texel the
// caster would write (what lies between it and the sun is lit either way), so leaving
// the caster out of the map changes no pixel. Conservative: true may still mean no
// shadow in view; a sun at the horizon always gives true.
bool ShadowCanReach(const Eigen::Vector3f& centre, float radius, const Eigen::Vector3f& to_sun,
                    const std::array<Eigen::Vector4f, 6>& view_planes);

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

  // Whether the fixed casters' depth for `clip_from_world` is kept; if so,
  // BeginMoving uses it.
  bool FixedCastersCached(const Eigen::Matrix4f& clip_from_world);
  // Binds a framebuffer for the fixed casters' depth of `clip_from_world`
  // (the least recently used one) and the depth-only program, and clears
  // it; the caller draws them with ModelLocation() set per item.
  void BeginFixed(const Eigen::Matrix4f& clip_from_world);
  // Copies the fixed casters' depth found or drawn last into the map and
  // binds it for the moving casters, drawn the same way; then End().
  void BeginMoving(const Eigen::Matrix4f& clip_from_world);
  GLint ModelLocation() const { return u_model_; }
  // How the RGB pass samples what was drawn.
  ShadowSampling End(const Eigen::Matrix4f& clip_from_world) const;

 private:
  void Bind(GLuint framebuffer, const Eigen::Matrix4f& clip_from_world) const;

  GLsizei size_;
  float radius_m_;
  GLuint texture_ = 0, framebuffer_ = 0, program_ = 0;
  GLint u_model_ = -1, u_clip_from_world_ = -1;
  // Up to four cameras keep their own; more take turns (least recently used).
  static constexpr std::size_t kFixedEntries = 4;
  struct FixedDepth {
    GLuint texture = 0, framebuffer = 0;
    bool valid = false;
    Eigen::Matrix4f clip_from_world = Eigen::Matrix4f::Zero();
    uint64_t last_used = 0;
  };
  std::array<FixedDepth, kFixedEntries> fixed_;
  std::size_t current_ = 0;  // the entry BeginMoving copies
  uint64_t uses_ = 0;
};

}  // namespace sim4cv::render
