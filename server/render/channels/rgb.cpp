// CHANNEL_RGB: the full look (look.h, shading.h): sun and sky light, shadows,
// procedural materials per semantic class, fog and exposure; with
// --quality fast (a program compiled without SIM4CV_FULL_LOOK), Lambert
// shading of the vertex colour under one light.
// Gamma encoded for 8-bit output.
#include "server/render/channel_output.h"
#include "server/render/shading.h"

namespace sim4cv::render::outputs {

// The clear colour is the fast look's sky, already gamma encoded since clears
// bypass the shader; the full look draws the sky over it (sky_pass.h).
extern const ChannelOutput RGB{proto::CHANNEL_RGB, GL_RGBA8, GL_RGB, GL_UNSIGNED_BYTE, false,
                               {0.62f, 0.76f, 0.90f, 1.0f}, {}, "vec4", R"(
#ifdef SIM4CV_FULL_LOOK
  OUT = ShadeFull(v_color, v_world_normal, v_world_position, v_semantic, v_fog);  // class and flags
#else
  const float kAmbient = 0.35;
  float lambert = max(dot(normalize(v_world_normal), u_to_light), 0.0);
  vec3 linear_rgb = v_color * (kAmbient + (1.0 - kAmbient) * lambert);
  OUT = vec4(pow(linear_rgb, vec3(1.0 / 2.2)), 1.0);
#endif
)", kShadingGlsl, /*reads_look=*/true};

}  // namespace sim4cv::render::outputs
