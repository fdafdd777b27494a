#include "server/transport/http/ws_frame_writer.h"

#include "server/common/check.h"
#include "server/transport/frame_encoding.h"
#include "server/transport/http/json_envelope.h"

namespace sim4cv::transport {

void WsFrameWriter::Build(const session::Frame& frame, const session::ClientSession& session,
                          const WsViewOptions& view) {
  const session::ClientProtocol& protocol = session.protocol();
  bool with_boxes = false;
  for (int channel : protocol.subscription().channels()) with_boxes = with_boxes || channel == proto::CHANNEL_BOXES;
  proto::Frame& meta = *envelope_.mutable_frame();
  meta.Clear();
  FillFrameMeta(frame, frame.camera_name, with_boxes, protocol.with_state(), session.dropped(), meta);

  binary_.clear();
  binary_bytes_ = 0;
  const std::size_t pixel_count = static_cast<std::size_t>(frame.width) * frame.height;
  for (int channel : protocol.subscription().channels()) {
    const channels::ChannelInfo* info = channels::Find(channel);
    if (info == nullptr) continue;  // BOXES
    const uint8_t* pixels = frame.Pixels(channel);
    // The sim thread renders every channel a subscriber of the camera asked for.
    SIM4CV_DEMAND(pixels != nullptr);
    proto::Image& image = *meta.add_images();
    image.set_channel(info->id);
    image.set_format(info->format);
    image.set_stride(frame.width * info->bytes_per_pixel);
    image.set_element(info->element);
    image.set_components(info->components);
    // One JPEG per frame at most (the encoder's buffer holds one): RGB.
    if (view.jpeg_rgb && channel == proto::CHANNEL_RGB) {
      const std::span<const uint8_t> jpeg = jpeg_.Encode(pixels, frame.width, frame.height, view.jpeg_quality);
      image.set_encoding(proto::IMAGE_ENCODING_JPEG);
      image.set_binary_bytes(static_cast<uint32_t>(jpeg.size()));
      binary_.emplace_back(jpeg.data(), jpeg.size());
    } else {
      const std::size_t size = pixel_count * info->bytes_per_pixel;
      image.set_binary_bytes(static_cast<uint32_t>(size));
      binary_.emplace_back(pixels, size);
    }
    binary_bytes_ += binary_.back().size();
  }
  EnvelopeToJson(envelope_, header_);
}

}  // namespace sim4cv::transport
