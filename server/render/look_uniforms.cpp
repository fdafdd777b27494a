#include "server/render/look_uniforms.h"

namespace sim4cv::render {

void LookUniforms::Locate(GLuint program) {
  const auto locate = [&](const char* name) { return glGetUniformLocation(program, name); };
  sun_ = locate("u_sun");
  sky_zenith_ = locate("u_sky_zenith");
  sky_horizon_ = locate("u_sky_horizon");
  ambient_sky_ = locate("u_ambient_sky");
  ambient_ground_ = locate("u_ambient_ground");
  fog_ = locate("u_fog");
  variation_ = locate("u_variation");
  noise_ = locate("u_noise");
  noise_seed_ = locate("u_noise_seed");
  weather_ = locate("u_weather");
  camera_position_ = locate("u_camera_position");
  shadow_from_world_ = locate("u_shadow_from_world");
  shadow_map_ = locate("u_shadow_map");
  to_light_ = locate("u_to_light");
}

void LookUniforms::Apply(const Look& look, const Eigen::Vector3f& camera_position, const ShadowSampling& shadow,
                         uint32_t noise_seed) const {
  glUniform3fv(sun_, 1, look.sun.data());
  glUniform3fv(sky_zenith_, 1, look.sky_zenith.data());
  glUniform3fv(sky_horizon_, 1, look.sky_horizon.data());
  glUniform3fv(ambient_sky_, 1, look.ambient_sky.data());
  glUniform3fv(ambient_ground_, 1, look.ambient_ground.data());
  glUniform4f(fog_, look.fog_colour.x(), look.fog_colour.y(), look.fog_colour.z(), look.fog_density);
  glUniform1ui(variation_, look.variation);
  glUniform2f(noise_, look.noise_read / 255.0f, look.noise_shot / 255.0f);  // in [0, 1] units
  glUniform1ui(noise_seed_, noise_seed);
  glUniform4f(weather_, look.clouds, look.wetness, look.lights, look.exposure);
  glUniform3fv(camera_position_, 1, camera_position.data());
  glUniformMatrix4fv(shadow_from_world_, 1, GL_FALSE, shadow.shadow_from_world.data());
  glUniform1i(shadow_map_, kShadowTextureUnit);
  glUniform3fv(to_light_, 1, look.to_sun.data());
}

}  // namespace sim4cv::render
