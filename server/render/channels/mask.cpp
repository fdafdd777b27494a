// CHANNEL_MASK: the draw item's instance id (0: unlabelled). The boxes are
// extracted from it, so it is rendered whenever BOXES is subscribed too.
#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput MASK{proto::CHANNEL_MASK, GL_R16UI, GL_RED_INTEGER, GL_UNSIGNED_SHORT, true,
                                {}, {0, 0, 0, 0}, "uint", R"(
  OUT = u_instance;
)"};

}  // namespace sim4cv::render::outputs
