// CHANNEL_SEMANTIC: the vertex's semantic class (render_types.h Vertex::semantic,
// semantic_classes.h), so one mesh can hold road and lane markings; sky (10)
// where nothing is drawn.
#include "server/render/channel_output.h"

namespace sim4cv::render::outputs {

extern const ChannelOutput SEMANTIC{proto::CHANNEL_SEMANTIC, GL_R8UI, GL_RED_INTEGER, GL_UNSIGNED_BYTE, true,
                                    {}, {10, 0, 0, 0}, "uint", R"(
  OUT = v_semantic & 255u;  // the class; higher bits are flags (render_types.h)
)"};

}  // namespace sim4cv::render::outputs
