#include "server/render/sky_pass.h"

#include <Eigen/LU>
#include <string>

#include "server/render/gl_program.h"
#include "server/render/shading.h"

namespace sim4cv::render {
namespace {

// One triangle covering the viewport, at the far plane (z = w).
constexpr const char* kVertexShader = R"(#version 330 core
out vec2 v_clip;
void main() {
  v_clip = vec2(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1));
  gl_Position = vec4(v_clip, 1.0, 1.0);
}
)";

// Sensor noise is compiled in: with u_noise 0 it adds nothing, and the sky
// is a few pixels of most frames.
constexpr const char* kFragmentHeader = R"(#version 330 core
#define SIM4CV_SENSOR_NOISE
in vec2 v_clip;
uniform mat4 u_world_from_clip;
uniform vec3 u_to_light;
uniform uint u_instance;  // shading.h's Vary reads it; the sky is no object
layout(location = 0) out vec4 out_rgb;
)";

constexpr const char* kFragmentMain = R"(
void main() {
  vec4 far_point = u_world_from_clip * vec4(v_clip, 1.0, 1.0);
  vec3 d = normalize(far_point.xyz / far_point.w - u_camera_position);
  // Fog thickens towards the horizon, where the line of sight is longest.
  float fog = 1.0 - exp(-u_fog.a * 150.0 / (max(d.z, 0.0) + 0.15));
  out_rgb = Expose(Sky(d), fog);
}
)";

}  // namespace

SkyPass::SkyPass() {
  const std::string fragment = std::string(kFragmentHeader) + kShadingGlsl + kFragmentMain;
  program_ = LinkProgram(kVertexShader, fragment.c_str());
  u_world_from_clip_ = RequireUniform(program_, "u_world_from_clip");
  look_.Locate(program_);
}

SkyPass::~SkyPass() { glDeleteProgram(program_); }

void SkyPass::Draw(GLuint rgb_attachment, const Eigen::Matrix4f& clip_from_world,
                   const Eigen::Vector3f& camera_position, const Look& look, uint32_t noise_seed) const {
  const GLenum buffer = GL_COLOR_ATTACHMENT0 + rgb_attachment;
  glDrawBuffers(1, &buffer);
  glUseProgram(program_);
  const Eigen::Matrix4f world_from_clip = clip_from_world.inverse();
  glUniformMatrix4fv(u_world_from_clip_, 1, GL_FALSE, world_from_clip.data());
  look_.Apply(look, camera_position, ShadowSampling{}, noise_seed);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);  // only where the depth buffer still holds the clear value
  glDepthMask(GL_FALSE);
  glDisable(GL_CULL_FACE);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glDepthFunc(GL_LESS);
  glEnable(GL_CULL_FACE);
}

}  // namespace sim4cv::render
