#include "server/transport/shm/shm_ring_writer.h"

#include <algorithm>
#include <array>
#include <cstring>

namespace sim4cv::transport {
namespace {

// One pixel plane of a frame as the ring stores it: where it comes from and
// where it goes in a slot (offset 0: the ring does not carry the channel).
struct Plane {
  proto::Channel channel;
  proto::PixelFormat format;
  uint32_t bytes_per_pixel;
  const void* data;
  std::size_t available_bytes;  // in the frame's buffer
  uint64_t offset;              // in the slot
};

// The frame's planes in channel-record order (RGB, DEPTH, MASK).
std::array<Plane, 3> Planes(const session::Frame& f, const shm::Geometry& g) {
  return {{{proto::CHANNEL_RGB, proto::PIXEL_FORMAT_RGB8, 3, f.rgb.data(), f.rgb.size(), g.rgb_offset},
           {proto::CHANNEL_DEPTH, proto::PIXEL_FORMAT_DEPTH_F32, 4, f.depth.data(), f.depth.size() * sizeof(float),
            g.depth_offset},
           {proto::CHANNEL_MASK, proto::PIXEL_FORMAT_INSTANCE_U16, 2, f.mask.data(), f.mask.size() * sizeof(uint16_t),
            g.mask_offset}}};
}

// The record of a plane the ring carries; one it does not carry stays all
// zero (docs/protocol.md 13.2), so no reader can follow it anywhere.
void SetChannel(shm::ShmChannel& out, const Plane& plane, uint32_t width, uint32_t height) {
  out = {};
  if (plane.offset == 0) return;
  out.channel = plane.channel;
  out.format = plane.format;
  out.bytes_per_pixel = plane.bytes_per_pixel;
  out.stride = width * plane.bytes_per_pixel;
  out.offset = plane.offset;
  out.bytes = static_cast<uint64_t>(out.stride) * height;
}

void CopyVec3(const proto::Vec3& v, double* out) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}

void FillEntities(const proto::State& state, shm::ShmFrameHeader& h) {
  const int count = std::min(state.entities_size(), static_cast<int>(shm::kShmMaxEntities));
  for (int i = 0; i < count; ++i) {
    const proto::EntityState& e = state.entities(i);
    shm::ShmEntityPose& pose = h.entities[i];
    pose.id = e.id();
    pose.kind = static_cast<uint32_t>(e.kind());
    CopyVec3(e.position(), pose.position);
    pose.orientation[0] = e.orientation().w();
    pose.orientation[1] = e.orientation().x();
    pose.orientation[2] = e.orientation().y();
    pose.orientation[3] = e.orientation().z();
    CopyVec3(e.linear_velocity(), pose.linear_velocity);
    CopyVec3(e.angular_velocity(), pose.angular_velocity);
  }
  h.entity_count = static_cast<uint32_t>(count);
}

}  // namespace

ShmRingWriter::ShmRingWriter(std::shared_ptr<ShmRegion> region, uint32_t camera_index)
    : region_(std::move(region)), camera_index_(camera_index) {}

void ShmRingWriter::OfferFrame(const session::FrameRef& frame) { Write(*frame); }

void ShmRingWriter::Write(const session::Frame& frame) {
  const ShmRegion& region = *region_;
  const ShmRegionParams& params = region.params();
  const std::size_t pixels = static_cast<std::size_t>(params.width) * params.height;
  if (frame.camera_index != camera_index_ || frame.width != params.width || frame.height != params.height) return;
  const std::array<Plane, 3> planes = Planes(frame, region.geometry());
  for (const Plane& plane : planes) {
    if (plane.offset != 0 && plane.available_bytes < pixels * plane.bytes_per_pixel) return;
  }
  // Every address comes from the daemon's own geometry; nothing is read back from the object.
  const shm::FrameMap& map = region.map();
  shm::ShmHeader& header = map.header();
  const uint64_t publication = published_ + 1;
  const uint64_t slot_index = publication - 1;  // FrameMap takes it modulo slot_count
  uint8_t* slot = map.slot_bytes(slot_index);
  shm::ShmFrameHeader& h = map.slot(slot_index);

  // Seqlock: odd while the slot changes, so readers discard what they copy
  // meanwhile. The value comes from the publication, not from the slot.
  auto sequence = shm::Atomic(h.sequence);
  sequence.store(2 * publication + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);

  h.publication = publication;
  h.frame_id = frame.frame_id;
  h.sim_time = frame.sim_time;
  h.render_end_mono_ns = frame.render_end_mono_ns;
  h.width = frame.width;
  h.height = frame.height;
  h.camera_index = frame.camera_index;
  h.channel_count = static_cast<uint32_t>(planes.size());
  h.channel_mask = params.channel_mask;
  // Only the channels the ring carries are copied: this memcpy is most of the
  // ring's latency, and a tracker that reads RGB alone needs a third of it.
  for (std::size_t i = 0; i < planes.size(); ++i) {
    SetChannel(h.channels[i], planes[i], frame.width, frame.height);
    if (planes[i].offset != 0) std::memcpy(slot + planes[i].offset, planes[i].data, h.channels[i].bytes);
  }

  const std::size_t boxes = std::min<std::size_t>(frame.boxes.size(), shm::kShmMaxBoxes);
  for (std::size_t i = 0; i < boxes; ++i) {
    const render::GroundTruthBox& in = frame.boxes[i];
    h.boxes[i] = {in.instance, in.object_class, in.x, in.y, in.width, in.height, in.visibility, in.visible_pixels};
  }
  h.box_count = static_cast<uint32_t>(boxes);
  h.box_total = static_cast<uint32_t>(frame.boxes.size());
  FillEntities(frame.state, h);

  sequence.store(2 * publication + 2, std::memory_order_release);
  published_ = publication;
  // published first: a reader that sees newest_frame_id finds that frame (or a newer one) published.
  shm::Atomic(header.published).store(publication, std::memory_order_release);
  shm::Atomic(header.newest_frame_id).store(frame.frame_id, std::memory_order_release);
  // Clients cannot write the object, so the daemon alone changes this word;
  // it wakes unconditionally (no waiter count a client could have zeroed).
  shm::Atomic(header.frame_futex).fetch_add(1, std::memory_order_seq_cst);
  shm::FutexWake(header.frame_futex, 0x7fffffff);
}

void ShmRingWriter::Close() {
  shm::ShmHeader& header = region_->header();
  shm::Atomic(header.closed).store(1, std::memory_order_release);
  shm::Atomic(header.frame_futex).fetch_add(1, std::memory_order_seq_cst);
  shm::FutexWake(header.frame_futex, 0x7fffffff);
}

}  // namespace sim4cv::transport
