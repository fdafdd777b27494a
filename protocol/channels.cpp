#include "protocol/channels.h"

namespace sim4cv::channels {

std::string ValidList() {
  std::string list;
  for (const ChannelInfo& info : kPixelChannels) {
    list += std::to_string(info.id) + " (" + proto::Channel_Name(info.id).substr(8) + "), ";
  }
  return list + "and " + std::to_string(proto::CHANNEL_BOXES) + " (BOXES)";
}

}  // namespace sim4cv::channels
