// CHANNEL_DEPTH: camera-space z, which is affine over a triangle, so the
// interpolated value is exact; +inf where nothing is drawn.
#include <limits>

#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput DEPTH{proto::CHANNEL_DEPTH, GL_R32F, GL_RED, GL_FLOAT, false,
                                 {std::numeric_limits<float>::infinity(), 0, 0, 0}, {}, "float", R"(
  OUT = v_depth;
)"};

}  // namespace sim4cv::render::outputs
