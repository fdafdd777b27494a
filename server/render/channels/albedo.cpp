// CHANNEL_ALBEDO: the colour of the surface itself, before any light: no
// sun, shade, shadow, sky reflection, lamps, fog, exposure or sensor noise.
// In the full look it is the very material RGB lights (shading.h,
// SurfaceAt: the procedural pattern per semantic class, the colour
// variation, a wet ground's darkening); in the fast look (--quality fast)
// the vertex colour that look shades. Gamma 2 in both, a square root as the
// full look's RGB (shading.h, Expose): pow(x, 1 / 2.2) doubled the channel's
// cost on llvmpipe (docs/benchmarks.md). So linear albedo is (value / 255)^2.
// Sky, and wherever nothing was hit: 0, 0, 0.
#include "server/render/channel_output.h"
#include "server/render/shading.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput ALBEDO{proto::CHANNEL_ALBEDO, GL_RGBA8, GL_RGB, GL_UNSIGNED_BYTE, false,
                                  {0.0f, 0.0f, 0.0f, 1.0f}, {}, "vec4", R"(
#ifdef SIM4CV_FULL_LOOK
  vec3 albedo = SurfaceAt(v_color, normalize(v_world_normal), v_world_position, v_semantic & 255u).albedo;
#else
  vec3 albedo = v_color;
#endif
  OUT = vec4(sqrt(clamp(albedo, 0.0, 1.0)), 1.0);
)", kShadingGlsl, /*reads_look=*/true};

}  // namespace sim4cv::render::outputs
