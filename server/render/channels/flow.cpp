// CHANNEL_FLOW: where this fragment's surface point was in the camera's
// previous frame, from the vertex's previous world transform and the
// camera's previous pose (DrawItem / CameraView `previous_*`), so camera and
// object motion both count. gl_FragCoord is the pixel centre in image
// coordinates (the projection mirrors y, so window rows are image rows); the
// previous position is the same mapping of the previous clip position.
// Points behind the previous camera have no previous pixel: NaN. Sky: 0, 0.
#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput FLOW{proto::CHANNEL_FLOW, GL_RG32F, GL_RG, GL_FLOAT, false, {0, 0, 0, 0}, {}, "vec2", R"(
  if (v_previous_clip.w <= 0.0) {
    OUT = vec2(uintBitsToFloat(0x7fc00000u));
  } else {
    vec2 previous = (v_previous_clip.xy / v_previous_clip.w * 0.5 + 0.5) * u_viewport;
    OUT = gl_FragCoord.xy - previous;
  }
)"};

}  // namespace sim4cv::render::outputs
