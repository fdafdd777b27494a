#include "server/transport/frame_encoding.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/wire_format_lite.h>

#include <algorithm>

#include "protocol/framing.h"
#include "server/common/check.h"
#include "server/wire/proto_math.h"

namespace sim4cv::transport {
namespace {

using google::protobuf::internal::WireFormatLite;
using google::protobuf::io::CodedOutputStream;

constexpr uint32_t kEnvelopeFrameTag =
    WireFormatLite::MakeTag(proto::Envelope::kFrameFieldNumber, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
constexpr uint32_t kFrameImagesTag =
    WireFormatLite::MakeTag(proto::Frame::kImagesFieldNumber, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);
constexpr uint32_t kImageDataTag =
    WireFormatLite::MakeTag(proto::Image::kDataFieldNumber, WireFormatLite::WIRETYPE_LENGTH_DELIMITED);

void AppendVarint(std::string& out, uint32_t value) {
  uint8_t buffer[5];
  const uint8_t* end = CodedOutputStream::WriteVarint32ToArray(value, buffer);
  out.append(reinterpret_cast<const char*>(buffer), static_cast<std::size_t>(end - buffer));
}

std::size_t VarintSize(std::size_t value) { return CodedOutputStream::VarintSize32(static_cast<uint32_t>(value)); }

struct PixelChannel {
  const channels::ChannelInfo* info = nullptr;
  const uint8_t* data = nullptr;
};

void FillImageHeader(const channels::ChannelInfo& info, uint32_t width, proto::Image& image) {
  image.Clear();
  image.set_channel(info.id);
  image.set_format(info.format);
  image.set_stride(width * info.bytes_per_pixel);
  image.set_element(info.element);
  image.set_components(info.components);
}

using wire::SetQuaternion;
using wire::SetVec3;

void FillCamera(const render::CameraIntrinsics& intrinsics, const render::Pose& pose, proto::Frame& meta) {
  proto::CameraIntrinsics& out = *meta.mutable_camera_intrinsics();
  out.set_fx(intrinsics.fx);
  out.set_fy(intrinsics.fy);
  out.set_cx(intrinsics.cx);
  out.set_cy(intrinsics.cy);
  out.set_width(intrinsics.width);
  out.set_height(intrinsics.height);
  out.set_k1(intrinsics.lens.k1);
  out.set_k2(intrinsics.lens.k2);
  out.set_p1(intrinsics.lens.p1);
  out.set_p2(intrinsics.lens.p2);
  out.set_k3(intrinsics.lens.k3);
  SetVec3(pose.position, *meta.mutable_camera_pose()->mutable_position());
  SetQuaternion(pose.orientation, *meta.mutable_camera_pose()->mutable_orientation());
}

void FillObject(const render::ObjectGroundTruth& object, proto::ObjectGroundTruth& out) {
  out.set_object_id(object.instance);
  out.set_object_class(static_cast<proto::ObjectClass>(object.object_class));
  SetVec3(object.position, *out.mutable_position());
  SetQuaternion(object.orientation, *out.mutable_orientation());
  SetVec3(object.linear_velocity, *out.mutable_linear_velocity());
  SetVec3(object.angular_velocity, *out.mutable_angular_velocity());
  SetVec3(object.half_extents, *out.mutable_half_extents());
  proto::ImageBox& box = *out.mutable_projected_box();
  box.set_x(object.projected_box.x);
  box.set_y(object.projected_box.y);
  box.set_width(object.projected_box.width);
  box.set_height(object.projected_box.height);
  out.set_has_visible_box(object.has_visible_box);
}

}  // namespace

void FillFrameMeta(const session::Frame& frame, const std::string& camera_name, bool with_boxes, bool with_state,
                   uint64_t dropped, proto::Frame& meta) {
  meta.set_frame_id(frame.frame_id);
  meta.set_sim_time(frame.sim_time);
  meta.set_camera(camera_name);
  meta.set_width(frame.width);
  meta.set_height(frame.height);
  meta.set_dropped_frames(dropped);
  meta.set_render_end_mono_ns(frame.render_end_mono_ns);
  if (with_state) *meta.mutable_state() = frame.state;
  if (!with_boxes) return;
  for (const auto& box : frame.boxes) {
    proto::Box* out = meta.add_boxes();
    out->set_object_id(box.instance);
    out->set_object_class(static_cast<proto::ObjectClass>(box.object_class));
    out->set_x(box.x);
    out->set_y(box.y);
    out->set_width(box.width);
    out->set_height(box.height);
    out->set_visibility(box.visibility);
    out->set_visible_pixels(box.visible_pixels);
  }
  FillCamera(frame.intrinsics, frame.camera_pose, meta);
  for (const auto& object : frame.objects) FillObject(object, *meta.add_objects());
}

namespace {

// A small frame's meta (no objects, a short State) fits well inside.
constexpr std::size_t kFirstArenaBlockBytes = 16 * 1024;

}  // namespace

proto::Frame& FrameEncoder::FreshMeta() {
  if (arena_ && arena_->SpaceAllocated() <= arena_block_.size()) {
    arena_->Reset();  // keeps the block we own
  } else {
    // The last frame overflowed into blocks of the arena's own: start over
    // with one block large enough (this allocates only while frames grow).
    const std::size_t needed = arena_ ? 2 * static_cast<std::size_t>(arena_->SpaceAllocated()) : kFirstArenaBlockBytes;
    arena_.reset();
    arena_block_.resize(std::max(needed, arena_block_.size()));
    google::protobuf::ArenaOptions options;
    options.initial_block = arena_block_.data();
    options.initial_block_size = arena_block_.size();
    arena_.emplace(options);
  }
  return *google::protobuf::Arena::CreateMessage<proto::Frame>(&*arena_);
}

void FrameEncoder::Encode(const session::Frame& frame, const session::ClientSession& session, bool length_prefix) {
  const session::ClientProtocol& protocol = session.protocol();
  Encode(frame, frame.camera_name, protocol.subscription(), protocol.with_state(), session.dropped(), length_prefix);
}

void FrameEncoder::Encode(const session::Frame& frame, const std::string& camera_name,
                          const proto::Subscribed& subscription, bool with_state, uint64_t dropped,
                          bool length_prefix) {
  bool with_boxes = false;
  for (int channel : subscription.channels()) with_boxes = with_boxes || channel == proto::CHANNEL_BOXES;
  proto::Frame& meta = FreshMeta();
  FillFrameMeta(frame, camera_name, with_boxes, with_state, dropped, meta);

  // Pass 1: sizes, since each length-delimited field is preceded by its size.
  const std::size_t pixel_count = static_cast<std::size_t>(frame.width) * frame.height;
  std::size_t frame_body = meta.ByteSizeLong();
  constexpr std::size_t kMax = channels::kPixelChannelCount;
  std::array<std::size_t, kMax> image_header_size{};
  std::array<std::size_t, kMax> image_data_size{};
  std::array<PixelChannel, kMax> pixel_channels{};
  std::size_t image_count = 0;
  for (int channel : subscription.channels()) {
    const channels::ChannelInfo* info = channels::Find(channel);
    if (info == nullptr) continue;  // BOXES
    const PixelChannel pixels{info, frame.Pixels(channel)};
    // The sim thread renders every channel a subscriber of the camera asked for.
    SIM4CV_DEMAND(pixels.data != nullptr && image_count < kMax);
    FillImageHeader(*info, frame.width, image_);
    const std::size_t data_size = pixel_count * info->bytes_per_pixel;
    const std::size_t image_body =
        image_.ByteSizeLong() + VarintSize(kImageDataTag) + VarintSize(data_size) + data_size;
    frame_body += VarintSize(kFrameImagesTag) + VarintSize(image_body) + image_body;
    image_header_size[image_count] = image_body - data_size;
    image_data_size[image_count] = data_size;
    pixel_channels[image_count] = pixels;
    ++image_count;
  }
  const std::size_t envelope_size = VarintSize(kEnvelopeFrameTag) + VarintSize(frame_body) + frame_body;

  // Pass 2: header bytes in wire order, remembering where pixels go between them.
  headers_.clear();
  if (length_prefix) {
    uint8_t prefix[wire::kLengthPrefixBytes];
    wire::EncodeLengthPrefix(static_cast<uint32_t>(envelope_size), prefix);
    headers_.append(reinterpret_cast<const char*>(prefix), sizeof prefix);
  }
  AppendVarint(headers_, kEnvelopeFrameTag);
  AppendVarint(headers_, static_cast<uint32_t>(frame_body));
  meta.AppendToString(&headers_);
  std::array<std::size_t, kMax> header_end{};
  for (std::size_t i = 0; i < image_count; ++i) {
    FillImageHeader(*pixel_channels[i].info, frame.width, image_);
    AppendVarint(headers_, kFrameImagesTag);
    AppendVarint(headers_, static_cast<uint32_t>(image_header_size[i] + image_data_size[i]));
    image_.AppendToString(&headers_);
    AppendVarint(headers_, kImageDataTag);
    AppendVarint(headers_, static_cast<uint32_t>(image_data_size[i]));
    header_end[i] = headers_.size();
  }

  // headers_ no longer grows, so pointers into it stay valid.
  segment_count_ = 0;
  std::size_t start = 0;
  const auto* header_bytes = reinterpret_cast<const uint8_t*>(headers_.data());
  for (std::size_t i = 0; i < image_count; ++i) {
    segments_[segment_count_++] = {header_bytes + start, header_end[i] - start};
    segments_[segment_count_++] = {pixel_channels[i].data, image_data_size[i]};
    start = header_end[i];
  }
  if (start < headers_.size() || segment_count_ == 0)
    segments_[segment_count_++] = {header_bytes + start, headers_.size() - start};
  total_size_ = headers_.size();
  for (std::size_t i = 0; i < image_count; ++i) total_size_ += image_data_size[i];
  SIM4CV_ASSERT(total_size_ == envelope_size + (length_prefix ? wire::kLengthPrefixBytes : 0));
}

}  // namespace sim4cv::transport
