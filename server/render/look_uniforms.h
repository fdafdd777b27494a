// The uniforms of shading.h in one GL program, and how a Look fills them.
// Needs a current GL context.
#pragma once

#define GL_GLEXT_PROTOTYPES
#include <GL/gl.h>
#include <GL/glext.h>

#include <Eigen/Core>

#include "server/render/look.h"

namespace sim4cv::render {

// The shadow map a frame is lit with (shadow_map.h); texture 0: none.
struct ShadowSampling {
  GLuint texture = 0;
  Eigen::Matrix4f shadow_from_world = Eigen::Matrix4f::Identity();  // to the map's [0,1]^3
};

// The texture unit the shadow map is bound to while drawing.
inline constexpr GLint kShadowTextureUnit = 1;

class LookUniforms {
 public:
  // Finds the uniforms in `program` (those it does not use stay -1).
  void Locate(GLuint program);
  // Sets them in the current program (which must be the located one).
  void Apply(const Look& look, const Eigen::Vector3f& camera_position, const ShadowSampling& shadow,
             uint32_t noise_seed) const;

 private:
  GLint sun_ = -1, sky_zenith_ = -1, sky_horizon_ = -1, ambient_sky_ = -1, ambient_ground_ = -1, fog_ = -1;
  GLint variation_ = -1, noise_ = -1, noise_seed_ = -1;
  GLint weather_ = -1, camera_position_ = -1, shadow_from_world_ = -1;
  GLint shadow_map_ = -1, to_light_ = -1;
};

}  // namespace sim4cv::render
