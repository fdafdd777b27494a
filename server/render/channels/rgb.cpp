// CHANNEL_RGB: Lambert shading of the vertex colour under one directional
// light plus ambient, gamma encoded for 8-bit output.
#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

// The clear colour is the sky, already gamma encoded since clears bypass the shader.
extern const ChannelOutput RGB{proto::CHANNEL_RGB, GL_RGBA8, GL_RGB, GL_UNSIGNED_BYTE, false,
                               {0.62f, 0.76f, 0.90f, 1.0f}, {}, "vec4", R"(
  const float kAmbient = 0.35;
  float lambert = max(dot(normalize(v_world_normal), u_to_light), 0.0);
  vec3 linear_rgb = v_color * (kAmbient + (1.0 - kAmbient) * lambert);
  OUT = vec4(pow(linear_rgb, vec3(1.0 / 2.2)), 1.0);
)"};

}  // namespace sim4cv::render::outputs
