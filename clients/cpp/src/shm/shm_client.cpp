// sim4cv::ShmClient, frame side: mapping and checking the object, seqlock
// reads of the frame ring, and waiting on its futex. The request side is in
// shm_requests.cpp.
#include "sim4cv/shm_client.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <random>

#include "protocol/shm_sync.h"

namespace sim4cv {
namespace {

// The part of a slot's header a reader copies (everything but the reserved tail).
constexpr std::size_t kFrameHeaderCopyBytes = offsetof(shm::ShmFrameHeader, reserved1);
std::string Printable(const char* bytes, std::size_t size) {
  std::string out;
  for (std::size_t i = 0; i < size; ++i) {
    const auto c = static_cast<unsigned char>(bytes[i]);
    if (c >= 32 && c < 127) {
      out += static_cast<char>(c);
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    }
  }
  return out;
}

// The pixel channels a ring carries. Daemons that predate --shm-channels left
// the header's mask 0 and always carried all three.
uint32_t RingChannels(const shm::ShmHeader& h) {
  return h.channel_mask == 0 ? shm::kShmAllPixelChannels : h.channel_mask;
}

bool InMask(uint32_t mask, proto::Channel channel) {
  return channel >= proto::CHANNEL_RGB && channel <= proto::CHANNEL_MASK &&
         (mask & shm::ChannelBit(static_cast<uint32_t>(channel))) != 0;
}

// Every offset the client will follow must stay inside the mapping.
void CheckGeometry(const shm::ShmHeader& h, std::size_t mapped, const std::string& name) {
  auto fail = [&](const std::string& what) {
    throw ShmError("shared-memory object " + name + " has a broken header: " + what);
  };
  if (h.header_bytes != shm::kShmHeaderBytes || h.frame_header_bytes != shm::kShmFrameHeaderBytes ||
      h.reply_slot_bytes != shm::kShmReplySlotBytes || h.response_message_bytes != shm::kShmResponseMessageBytes ||
      h.response_depth != shm::kShmResponseDepth) {
    fail("its record sizes differ from layout version " + std::to_string(shm::kShmLayoutVersion));
  }
  if (h.camera_width == 0 || h.camera_height == 0 || h.camera_width > 65536 || h.camera_height > 65536) {
    fail("camera size " + std::to_string(h.camera_width) + "x" + std::to_string(h.camera_height) + " is out of range");
  }
  if ((h.channel_mask & ~shm::kShmAllPixelChannels) != 0) {
    fail("its channel mask " + std::to_string(h.channel_mask) + " names channels other than RGB, DEPTH and MASK");
  }
  if (h.total_bytes > mapped) {
    fail("it claims " + std::to_string(h.total_bytes) + " bytes but the object has " + std::to_string(mapped));
  }
  const shm::Geometry g = shm::ComputeGeometry(h.camera_width, h.camera_height, h.slot_count, h.reply_capacity,
                                               h.response_entries, RingChannels(h));
  if (h.slot_count < 2 || h.reply_capacity == 0 || h.slot_bytes < g.slot_bytes || h.slots_offset < h.header_bytes ||
      h.slots_offset + h.slot_bytes * h.slot_count > h.total_bytes ||
      h.reply_offset + static_cast<uint64_t>(h.reply_capacity) * h.reply_slot_bytes > h.total_bytes ||
      h.response_entry_bytes < g.response_entry_bytes ||
      h.response_offset + h.response_entry_bytes * h.response_entries > h.total_bytes) {
    fail("its slot, reply or response offsets do not fit in " + std::to_string(h.total_bytes) + " bytes");
  }
}

// Copies channel record `index` (0 RGB, 1 DEPTH, 2 MASK) of `meta`, `count`
// values, into `out`; empties `out` if the frame lacks the channel. False if
// the record does not fit in the slot (sizes come from a possibly torn header).
template <typename T>
bool CopyPlane(std::vector<T>& out, const uint8_t* slot, uint64_t slot_bytes, const shm::ShmFrameHeader& meta,
               uint32_t index, std::size_t count) {
  const uint32_t channel = index + 1;
  if ((meta.channel_mask & shm::ChannelBit(channel)) == 0) {
    out.clear();  // keeps the capacity: a reused OwnedFrame allocates nothing
    return true;
  }
  const shm::ShmChannel& record = meta.channels[index];
  const uint64_t bytes = count * sizeof(T);
  if (record.channel != channel || record.offset < shm::kShmFrameHeaderBytes || record.offset + bytes > slot_bytes) {
    return false;
  }
  out.resize(count);
  std::memcpy(out.data(), slot + record.offset, std::min<uint64_t>(record.bytes, bytes));
  return true;
}

}  // namespace

bool FrameView::has(proto::Channel channel) const { return slot_ && InMask(header_.channel_mask, channel); }

bool OwnedFrame::has(proto::Channel channel) const { return InMask(channel_mask, channel); }

std::optional<ImageView> FrameView::image(proto::Channel channel) const {
  if (!has(channel)) return std::nullopt;  // an absent channel's record is zero: nothing to point at
  for (uint32_t i = 0; i < std::min(header_.channel_count, shm::kShmMaxChannels); ++i) {
    const shm::ShmChannel& c = header_.channels[i];
    if (c.channel != static_cast<uint32_t>(channel)) continue;
    return ImageView{slot_ + c.offset, header_.width, header_.height, c.stride,
                     static_cast<proto::PixelFormat>(c.format)};
  }
  return std::nullopt;
}

bool FrameView::stale() const {
  if (!slot_) return true;
  auto& sequence = const_cast<shm::ShmFrameHeader*>(reinterpret_cast<const shm::ShmFrameHeader*>(slot_))->sequence;
  std::atomic_thread_fence(std::memory_order_acquire);  // pixel reads before this check
  return shm::Atomic(sequence).load(std::memory_order_relaxed) != sequence_;
}

void FrameView::Validate() const {
  if (stale()) {
    throw ShmError("frame " + std::to_string(header_.frame_id) +
                   " was overwritten by the daemon while this view held it; its pixels may be torn");
  }
}

void FrameView::Release() { slot_ = nullptr; }

ShmClient::ShmClient() {
  std::random_device random;
  std::uniform_int_distribution<uint64_t> any(1, UINT64_MAX);
  token_ = any(random);
}

ShmClient::~ShmClient() { Close(); }

void ShmClient::Open(const std::string& name) {
  Close();
  const std::string path = !name.empty() && name[0] == '/' ? name : "/" + name;
  const int fd = shm_open(path.c_str(), O_RDWR, 0);
  if (fd < 0) {
    if (errno == ENOENT) {
      throw ShmError("no shared-memory object " + path + "; is sim4cvd running with --shm-name " + path.substr(1) +
                     "?");
    }
    throw ShmError("cannot open shared-memory object " + path + ": " + std::strerror(errno));
  }
  struct stat info {};
  const bool sized = fstat(fd, &info) == 0;
  const auto size = sized ? static_cast<std::size_t>(info.st_size) : 0;
  if (size < sizeof(shm::ShmHeader)) {
    close(fd);
    throw ShmError("shared-memory object " + path + " is " + std::to_string(size) + " bytes, smaller than the " +
                   std::to_string(sizeof(shm::ShmHeader)) + "-byte sim4cv header: not a sim4cv ring");
  }
  void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  const int map_error = errno;
  close(fd);
  if (base == MAP_FAILED) throw ShmError("cannot map shared-memory object " + path + ": " + std::strerror(map_error));
  base_ = static_cast<uint8_t*>(base);
  mapped_bytes_ = size;
  name_ = path;
  try {
    const shm::ShmHeader& h = header();
    std::atomic_thread_fence(std::memory_order_acquire);  // the magic is written last
    if (std::memcmp(h.magic, SIM4CV_SHM_MAGIC, sizeof h.magic) != 0) {
      throw ShmError("shared-memory object " + path + " starts with '" + Printable(h.magic, sizeof h.magic) +
                     "', not the magic '" SIM4CV_SHM_MAGIC "': not a sim4cv ring (or the daemon is still creating it)");
    }
    if (h.layout_version != shm::kShmLayoutVersion) {
      throw ShmError("shared-memory object " + path + " has layout version " + std::to_string(h.layout_version) +
                     " but this client reads layout version " + std::to_string(shm::kShmLayoutVersion) +
                     "; use a client built for layout version " + std::to_string(h.layout_version));
    }
    CheckGeometry(h, size, path);
  } catch (...) {
    Close();
    throw;
  }
}

void ShmClient::Close() {
  if (base_) munmap(base_, mapped_bytes_);
  base_ = nullptr;
  mapped_bytes_ = 0;
  entry_ = -1;
  had_entry_ = false;
  next_response_ = 0;
  pending_.clear();
}

bool ShmClient::carries(proto::Channel channel) const {
  RequireOpen();
  return InMask(RingChannels(header()), channel);
}

std::string ShmClient::camera() const {
  RequireOpen();
  const auto& name = header().camera_name;
  return std::string(name, strnlen(name, sizeof name));
}

void ShmClient::RequireOpen() const {
  if (!base_) throw ShmError("ShmClient::Open must succeed before reading frames");
}

uint64_t ShmClient::newest_frame_id() const {
  RequireOpen();
  return shm::Atomic(const_cast<shm::ShmHeader&>(header()).newest_frame_id).load(std::memory_order_acquire);
}

bool ShmClient::closed() const {
  RequireOpen();
  return shm::Atomic(const_cast<shm::ShmHeader&>(header()).closed).load(std::memory_order_acquire) != 0;
}

bool ShmClient::AcquireNewest(FrameView& view) const {
  RequireOpen();
  const shm::Mapped map(base_);
  shm::ShmHeader& h = map.header();
  for (;;) {
    const uint64_t published = shm::Atomic(h.published).load(std::memory_order_acquire);
    if (published == 0) return false;
    const uint64_t slot = (published - 1) % h.slot_count;
    shm::ShmFrameHeader& frame = map.slot(slot);
    const uint64_t before = shm::Atomic(frame.sequence).load(std::memory_order_acquire);
    if (before & 1) continue;  // being written: the writer finishes in microseconds
    std::memcpy(&view.header_, &frame, kFrameHeaderCopyBytes);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (shm::Atomic(frame.sequence).load(std::memory_order_relaxed) != before) continue;
    view.header_.box_count = std::min(view.header_.box_count, shm::kShmMaxBoxes);
    view.header_.entity_count = std::min(view.header_.entity_count, shm::kShmMaxEntities);
    view.slot_ = map.slot_bytes(slot);
    view.sequence_ = before;
    return true;
  }
}

bool ShmClient::ReadNewest(OwnedFrame& frame) const { return CopyNewest(frame); }

bool ShmClient::CopyNewest(OwnedFrame& out) const {
  RequireOpen();
  const shm::Mapped map(base_);
  shm::ShmHeader& h = map.header();
  shm::ShmFrameHeader meta;
  for (;;) {
    const uint64_t published = shm::Atomic(h.published).load(std::memory_order_acquire);
    if (published == 0) return false;
    const uint64_t slot_index = (published - 1) % h.slot_count;
    const uint8_t* slot = map.slot_bytes(slot_index);
    shm::ShmFrameHeader& frame = map.slot(slot_index);
    const uint64_t before = shm::Atomic(frame.sequence).load(std::memory_order_acquire);
    if (before & 1) continue;
    std::memcpy(&meta, &frame, kFrameHeaderCopyBytes);
    // Sizes come from a possibly torn header: bound them by the slot before copying.
    const std::size_t pixels =
        static_cast<std::size_t>(std::min(meta.width, h.camera_width)) * std::min(meta.height, h.camera_height);
    const bool sane = meta.channel_count == 3 && CopyPlane(out.rgb, slot, h.slot_bytes, meta, 0, pixels * 3) &&
                      CopyPlane(out.depth, slot, h.slot_bytes, meta, 1, pixels) &&
                      CopyPlane(out.mask, slot, h.slot_bytes, meta, 2, pixels);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (shm::Atomic(frame.sequence).load(std::memory_order_relaxed) != before) continue;
    if (!sane)
      throw ShmError("frame slot " + std::to_string(slot_index) + " of " + name_ + " has inconsistent channels");
    out.frame_id = meta.frame_id;
    out.publication = meta.publication;
    out.sim_time = meta.sim_time;
    out.render_end_mono_ns = meta.render_end_mono_ns;
    out.width = meta.width;
    out.height = meta.height;
    out.channel_mask = meta.channel_mask;
    out.boxes.assign(meta.boxes, meta.boxes + std::min(meta.box_count, shm::kShmMaxBoxes));
    out.box_total = meta.box_total;
    out.entities.assign(meta.entities, meta.entities + std::min(meta.entity_count, shm::kShmMaxEntities));
    return true;
  }
}

bool ShmClient::WaitForFrame(uint64_t after_frame_id, Duration timeout) const {
  RequireOpen();
  shm::ShmHeader& h = const_cast<shm::ShmHeader&>(header());
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  const auto spin_end = std::chrono::steady_clock::now() + spin_;
  auto futex = shm::Atomic(h.frame_futex);
  auto waiters = shm::Atomic(h.frame_waiters);
  for (;;) {
    const uint32_t seen = futex.load(std::memory_order_seq_cst);
    if (newest_frame_id() > after_frame_id) return true;
    if (closed()) throw ConnectionError("sim4cvd stopped: the shared-memory ring " + name_ + " is closed");
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    if (now < spin_end) continue;
    // Announce, then re-check the word: the writer wakes whenever waiters > 0.
    waiters.fetch_add(1, std::memory_order_seq_cst);
    if (futex.load(std::memory_order_seq_cst) == seen) {
      shm::FutexWait(h.frame_futex, seen, std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - now).count());
    }
    waiters.fetch_sub(1, std::memory_order_seq_cst);
  }
}

}  // namespace sim4cv
