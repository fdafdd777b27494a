// CHANNEL_NORMALS: the interpolated normal in camera space, turned from GL's
// camera axes (x right, y up, looking along -z) into OpenCV's (x right,
// y down, z forward), the axes of Frame.camera_pose; 0,0,0 where nothing is drawn.
#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput NORMALS{proto::CHANNEL_NORMALS, GL_RGBA32F, GL_RGB, GL_FLOAT, false,
                                   {0, 0, 0, 0}, {}, "vec4", R"(
  vec3 n = normalize(v_camera_normal);
  OUT = vec4(n.x, -n.y, -n.z, 0.0);
)"};

}  // namespace sim4cv::render::outputs
