#include "server/render/shadow_map.h"

#include <algorithm>
#include <cmath>
#include <Eigen/Geometry>
#include <stdexcept>

#include "server/render/gl_program.h"

namespace sim4cv::render {
namespace {

constexpr const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
uniform mat4 u_model;
uniform mat4 u_clip_from_world;
void main() { gl_Position = u_clip_from_world * (u_model * vec4(a_position, 1.0)); }
)";
constexpr const char* kFragmentShader = R"(#version 330 core
void main() {}
)";

// Sun-space depth kept around the fitted square: casters up to this far
// towards the sun (tall buildings, UAVs) still cast.
constexpr float kDepthRangeM = 400.0f;
// The map's centre moves in steps this long (in the sun's frame): the fixed
// casters are redrawn about once per kSnapM the camera travels.
constexpr float kSnapM = 4.0f;

// A depth texture with a framebuffer that draws only into it.
void MakeDepthTarget(GLsizei size, GLuint& texture, GLuint& framebuffer) {
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_2D, texture);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT24, size, size, 0, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // linear (2x2 PCF) costs +0.5 ms a frame
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glGenFramebuffers(1, &framebuffer);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, texture, 0);
  glDrawBuffer(GL_NONE);
  glReadBuffer(GL_NONE);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
    throw std::runtime_error("shadow map framebuffer is incomplete");
  }
}

}  // namespace

bool ShadowCanReach(const Eigen::Vector3f& centre, float radius, const Eigen::Vector3f& to_sun,
                    const std::array<Eigen::Vector4f, 6>& view_planes) {
  // The margin covers a texel's footprint (0.18 m diagonal at 512 texels over 64 m),
  // the sampling's 0.06 m normal offset and rounding.
  constexpr float kMarginM = 0.5f;
  constexpr float kLowestReceiverZ = -5.0f;  // below any ground a map has
  if (to_sun.z() < 0.02f) return true;       // shadows without end
  const Eigen::Vector3f end = centre - to_sun * (std::max(centre.z() - kLowestReceiverZ, 0.0f) / to_sun.z());
  return std::all_of(view_planes.begin(), view_planes.end(), [&](const Eigen::Vector4f& plane) {
    const float farthest_inside = std::max(plane.head<3>().dot(centre), plane.head<3>().dot(end)) + plane.w();
    return farthest_inside >= -(radius + kMarginM);
  });
}

ShadowMap::ShadowMap(GLsizei size, float radius_m) : size_(size), radius_m_(radius_m) {
  MakeDepthTarget(size_, texture_, framebuffer_);
  for (FixedDepth& entry : fixed_) MakeDepthTarget(size_, entry.texture, entry.framebuffer);
  program_ = LinkProgram(kVertexShader, kFragmentShader);
  u_model_ = RequireUniform(program_, "u_model");
  u_clip_from_world_ = RequireUniform(program_, "u_clip_from_world");
  ThrowOnGlError("ShadowMap setup");
}

ShadowMap::~ShadowMap() {
  glDeleteProgram(program_);
  for (FixedDepth& entry : fixed_) {
    glDeleteFramebuffers(1, &entry.framebuffer);
    glDeleteTextures(1, &entry.texture);
  }
  glDeleteFramebuffers(1, &framebuffer_);
  glDeleteTextures(1, &texture_);
}

Eigen::Matrix4f ShadowMap::Fit(const CameraView& camera, const Eigen::Vector3f& to_sun) const {
  const Eigen::Vector3f eye = camera.world_from_camera.block<3, 1>(0, 3);
  const Eigen::Vector3f forward = -camera.world_from_camera.block<3, 1>(0, 2);
  // The square's centre: where the view meets the ground if it does nearby,
  // else a radius ahead of the camera.
  Eigen::Vector3f centre = eye + forward * radius_m_;
  if (forward.z() < -0.05f) {
    const float hit = -eye.z() / forward.z();
    if (hit < radius_m_ * 1.5f) centre = eye + forward * hit;
  }
  centre.z() = 0.0f;
  const Eigen::Vector3f z = to_sun.normalized();  // the sun looks along -z
  const Eigen::Vector3f up = std::abs(z.z()) > 0.99f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitZ();
  const Eigen::Vector3f x = up.cross(z).normalized();
  const Eigen::Vector3f y = z.cross(x);
  Eigen::Matrix4f sun_from_world = Eigen::Matrix4f::Identity();
  sun_from_world.block<1, 3>(0, 0) = x.transpose();
  sun_from_world.block<1, 3>(1, 0) = y.transpose();
  sun_from_world.block<1, 3>(2, 0) = z.transpose();
  // Snap the centre to steps of kSnapM (whole texels) in the sun's frame.
  const float texel_m = 2.0f * radius_m_ / static_cast<float>(size_);
  const float step_m = std::round(kSnapM / texel_m) * texel_m;
  Eigen::Vector3f snapped(x.dot(centre), y.dot(centre), 0.0f);
  snapped.x() = std::round(snapped.x() / step_m) * step_m;
  snapped.y() = std::round(snapped.y() / step_m) * step_m;
  sun_from_world.block<3, 1>(0, 3) = -snapped;
  Eigen::Matrix4f ortho = Eigen::Matrix4f::Identity();
  ortho(0, 0) = 1.0f / radius_m_;
  ortho(1, 1) = 1.0f / radius_m_;
  ortho(2, 2) = -1.0f / kDepthRangeM;  // z towards the sun is nearer
  return ortho * sun_from_world;
}

bool ShadowMap::FixedCastersCached(const Eigen::Matrix4f& clip_from_world) {
  for (std::size_t i = 0; i < fixed_.size(); ++i) {
    if (fixed_[i].valid && fixed_[i].clip_from_world == clip_from_world) {
      current_ = i;
      return true;
    }
  }
  return false;
}

void ShadowMap::Bind(GLuint framebuffer, const Eigen::Matrix4f& clip_from_world) const {
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, size_, size_);
  glUseProgram(program_);
  glUniformMatrix4fv(u_clip_from_world_, 1, GL_FALSE, clip_from_world.data());
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_CULL_FACE);  // open meshes (ground, signs) cast from both sides
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(1.5f, 2.0f);  // against self-shadowing stripes
}

void ShadowMap::BeginFixed(const Eigen::Matrix4f& clip_from_world) {
  current_ = 0;  // an unused entry, else the least recently used one
  for (std::size_t i = 1; i < fixed_.size(); ++i) {
    const FixedDepth& best = fixed_[current_];
    if (best.valid && (!fixed_[i].valid || fixed_[i].last_used < best.last_used)) current_ = i;
  }
  FixedDepth& entry = fixed_[current_];
  Bind(entry.framebuffer, clip_from_world);
  glClear(GL_DEPTH_BUFFER_BIT);
  entry.valid = true;
  entry.clip_from_world = clip_from_world;
}

void ShadowMap::BeginMoving(const Eigen::Matrix4f& clip_from_world) {
  FixedDepth& entry = fixed_[current_];
  entry.last_used = ++uses_;
  glCopyImageSubData(entry.texture, GL_TEXTURE_2D, 0, 0, 0, 0, texture_, GL_TEXTURE_2D, 0, 0, 0, 0, size_, size_, 1);
  Bind(framebuffer_, clip_from_world);
}

ShadowSampling ShadowMap::End(const Eigen::Matrix4f& clip_from_world) const {
  glDisable(GL_POLYGON_OFFSET_FILL);
  glActiveTexture(GL_TEXTURE0 + kShadowTextureUnit);
  glBindTexture(GL_TEXTURE_2D, texture_);
  glActiveTexture(GL_TEXTURE0);
  Eigen::Matrix4f to_unit = Eigen::Matrix4f::Identity() * 0.5f;  // clip [-1,1] -> [0,1]
  to_unit(3, 3) = 1.0f;
  to_unit.block<3, 1>(0, 3).setConstant(0.5f);
  return ShadowSampling{texture_, to_unit * clip_from_world};
}

}  // namespace sim4cv::render
