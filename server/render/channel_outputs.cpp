#include "server/render/channel_output.h"

namespace sim4cv::render {

// Each channel file defines render::outputs::<ENUM> (e.g. outputs::SEMANTIC).
namespace outputs {
#define SIM4CV_DECLARE_OUTPUT(ENUM, ...) extern const ChannelOutput ENUM;
SIM4CV_PIXEL_CHANNELS(SIM4CV_DECLARE_OUTPUT)
#undef SIM4CV_DECLARE_OUTPUT
}  // namespace outputs

#define SIM4CV_OUTPUT_ADDRESS(ENUM, ...) &outputs::ENUM,
const std::array<const ChannelOutput*, channels::kPixelChannelCount> kChannelOutputs = {
    SIM4CV_PIXEL_CHANNELS(SIM4CV_OUTPUT_ADDRESS)};
#undef SIM4CV_OUTPUT_ADDRESS

}  // namespace sim4cv::render
