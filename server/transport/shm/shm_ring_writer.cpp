#include "server/transport/shm/shm_ring_writer.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <utility>

namespace sim4cv::transport {
namespace {

// The record of plane `index` in a slot of the given geometry; a plane the
// ring does not carry stays all zero (docs/protocol.md 13.2), so no reader
// can follow it anywhere.
void SetChannel(shm::ShmChannel& out, std::size_t index, const shm::Geometry& g, uint32_t width, uint32_t height) {
  out = {};
  if (g.offsets[index] == 0) return;
  const channels::ChannelInfo& info = channels::kPixelChannels[index];
  out.channel = static_cast<uint32_t>(info.id);
  out.format = static_cast<uint32_t>(info.format);
  out.bytes_per_pixel = static_cast<uint16_t>(info.bytes_per_pixel);
  out.element = static_cast<uint8_t>(info.element);
  out.components = static_cast<uint8_t>(info.components);
  out.stride = width * info.bytes_per_pixel;
  out.offset = g.offsets[index];
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

// The seqlock: odd while the slot changes, so readers discard what they copy
// meanwhile. The value comes from the publication, not from the slot.
void ShmRingWriter::OpenSlot(uint64_t publication) {
  shm::ShmFrameHeader& h = region_->map().slot(publication - 1);  // FrameMap takes it modulo slot_count
  shm::Atomic(h.sequence).store(2 * publication + 1, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
}

bool ShmRingWriter::PrepareTargets(uint32_t camera_index, uint32_t width, uint32_t height,
                                   session::PixelTargets& targets) {
  const ShmRegionParams& params = region_->params();
  if (camera_index != camera_index_ || width != params.width || height != params.height) return false;
  OpenSlot(published_ + 1);
  uint8_t* slot = region_->map().slot_bytes(published_);
  const shm::Geometry& geometry = region_->geometry();
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    targets[i] = geometry.offsets[i] != 0 ? slot + geometry.offsets[i] : nullptr;
  }
  prepared_ = true;
  return true;
}

void ShmRingWriter::Write(const session::Frame& frame) {
  const ShmRegion& region = *region_;
  const ShmRegionParams& params = region.params();
  const std::size_t pixels = static_cast<std::size_t>(params.width) * params.height;
  if (frame.camera_index != camera_index_ || frame.width != params.width || frame.height != params.height) return;
  const shm::Geometry& geometry = region.geometry();
  const bool in_place = std::exchange(prepared_, false);
  for (std::size_t i = 0; i < channels::kPixelChannelCount && !in_place; ++i) {
    const channels::ChannelInfo& info = channels::kPixelChannels[i];
    if (geometry.offsets[i] != 0 &&
        (!channels::Has(frame.channels, info.id) || frame.planes[i].size() < pixels * info.bytes_per_pixel)) {
      return;
    }
  }
  // Every address comes from the daemon's own geometry; nothing is read back from the object.
  const shm::FrameMap& map = region.map();
  shm::ShmHeader& header = map.header();
  const uint64_t publication = published_ + 1;
  const uint64_t slot_index = publication - 1;  // FrameMap takes it modulo slot_count
  uint8_t* slot = map.slot_bytes(slot_index);
  shm::ShmFrameHeader& h = map.slot(slot_index);
  if (!in_place) OpenSlot(publication);
  auto sequence = shm::Atomic(h.sequence);

  h.publication = publication;
  h.frame_id = frame.frame_id;
  h.sim_time = frame.sim_time;
  h.render_end_mono_ns = frame.render_end_mono_ns;
  h.width = frame.width;
  h.height = frame.height;
  h.camera_index = frame.camera_index;
  h.channel_count = static_cast<uint32_t>(channels::kPixelChannelCount);
  h.channel_mask = params.channel_mask;
  for (std::size_t i = 0; i < channels::kPixelChannelCount; ++i) {
    SetChannel(h.channels[i], i, geometry, frame.width, frame.height);
    // Rendered in place, the pixels are there already; otherwise only the
    // channels the ring carries are copied (this memcpy was most of the ring's latency).
    if (!in_place && geometry.offsets[i] != 0) {
      std::memcpy(slot + geometry.offsets[i], frame.planes[i].data(), h.channels[i].bytes);
    }
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
