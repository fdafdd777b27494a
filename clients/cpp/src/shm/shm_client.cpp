// sim4cv::ShmClient, frame side: attaching through the daemon's Unix socket,
// mapping and checking the frame object (read-only) and this client's area,
// seqlock reads of the frame ring, and waiting on its futex. The request side
// is in shm_requests.cpp.
#include "sim4cv/shm_client.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>

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

// The pixel channels a ring carries (checked non-zero at Open).
uint32_t RingChannels(const shm::ShmHeader& h) { return h.channel_mask; }

bool InMask(uint32_t mask, proto::Channel channel) {
  return channels::Find(channel) != nullptr && channels::Has(mask, channel);
}

// The frame object's header against this client's layout and the object's
// size; returns the geometry the client then uses (its own copy).
shm::Geometry CheckFrames(const shm::ShmHeader& h, std::size_t mapped, const std::string& name) {
  auto fail = [&](const std::string& what) {
    throw ShmError("the shared-memory frame object of " + name + " has a broken header: " + what);
  };
  if (std::memcmp(h.magic, SIM4CV_SHM_MAGIC, sizeof h.magic) != 0) {
    fail("it starts with '" + Printable(h.magic, sizeof h.magic) + "', not the magic '" SIM4CV_SHM_MAGIC "'");
  }
  if (h.layout_version != shm::kShmLayoutVersion) {
    throw ShmError("the shared memory of " + name + " has layout version " + std::to_string(h.layout_version) +
                   " but this client reads layout version " + std::to_string(shm::kShmLayoutVersion) +
                   "; use a client built for layout version " + std::to_string(h.layout_version));
  }
  if (h.header_bytes != shm::kShmHeaderBytes || h.frame_header_bytes != shm::kShmFrameHeaderBytes) {
    fail("its record sizes differ from layout version " + std::to_string(shm::kShmLayoutVersion));
  }
  if (h.camera_width == 0 || h.camera_height == 0 || h.camera_width > 65536 || h.camera_height > 65536) {
    fail("camera size " + std::to_string(h.camera_width) + "x" + std::to_string(h.camera_height) + " is out of range");
  }
  if (h.channel_mask == 0 || (h.channel_mask & ~channels::kAllPixels) != 0) {
    fail("its channel mask " + std::to_string(h.channel_mask) + " is not a set of " + channels::Names(channels::kAllPixels));
  }
  const shm::Geometry g = shm::ComputeGeometry(h.camera_width, h.camera_height, h.slot_count, h.channel_mask);
  if (h.slot_count < 2 || h.slot_bytes != g.slot_bytes || h.slots_offset != g.slots_offset ||
      h.total_bytes != g.total_bytes || g.total_bytes > mapped) {
    fail("its slots (" + std::to_string(h.slot_count) + " of " + std::to_string(h.slot_bytes) +
         " bytes) do not match its camera size or do not fit in the object's " + std::to_string(mapped) + " bytes");
  }
  return g;
}

void CheckArea(const shm::ShmAreaHeader& h, const std::string& name) {
  if (std::memcmp(h.magic, SIM4CV_SHM_AREA_MAGIC, sizeof h.magic) != 0 || h.layout_version != shm::kShmLayoutVersion ||
      h.total_bytes != shm::kAreaBytes || h.request_offset != shm::kAreaRequestOffset ||
      h.request_capacity != shm::kShmRequestCapacity || h.request_slot_bytes != shm::kShmRequestSlotBytes ||
      h.response_offset != shm::kAreaResponseOffset || h.response_depth != shm::kShmResponseDepth ||
      h.response_message_bytes != shm::kShmResponseMessageBytes) {
    throw ShmError("the client area " + name + " handed over is not a layout version " +
                   std::to_string(shm::kShmLayoutVersion) + " area");
  }
}

// Receives the daemon's ShmAttach and its descriptors (up to 3) from `socket`.
void ReceiveAttach(int socket, shm::ShmAttach& attach, int (&fds)[3], int& fd_count, const std::string& name) {
  iovec data{&attach, sizeof attach};
  alignas(cmsghdr) char control[CMSG_SPACE(3 * sizeof(int))] = {};
  msghdr message{};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  message.msg_control = control;
  message.msg_controllen = sizeof control;
  const ssize_t got = recvmsg(socket, &message, MSG_CMSG_CLOEXEC);
  const int error = errno;
  fd_count = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(&message); c; c = CMSG_NXTHDR(&message, c)) {
    if (c->cmsg_level != SOL_SOCKET || c->cmsg_type != SCM_RIGHTS) continue;
    const auto n = static_cast<int>((c->cmsg_len - CMSG_LEN(0)) / sizeof(int));
    for (int i = 0; i < n; ++i) {
      int fd = -1;
      std::memcpy(&fd, CMSG_DATA(c) + static_cast<std::size_t>(i) * sizeof(int), sizeof fd);
      if (fd_count < 3) {
        fds[fd_count++] = fd;
      } else {
        close(fd);
      }
    }
  }
  auto fail = [&](const std::string& what) {
    for (int i = 0; i < fd_count; ++i) close(fds[i]);
    fd_count = 0;
    throw ShmError("attaching to the shared memory of " + name + ": " + what);
  };
  if (got < 0) fail(std::string("no answer from sim4cvd: ") + std::strerror(error));
  if (got != static_cast<ssize_t>(sizeof attach) || std::memcmp(attach.magic, SIM4CV_SHM_ATTACH_MAGIC, 8) != 0) {
    fail("the daemon's answer (" + std::to_string(got) + " bytes) is not a sim4cv attach message");
  }
  if (attach.layout_version != shm::kShmLayoutVersion) {
    fail("the daemon speaks layout version " + std::to_string(attach.layout_version) +
         " but this client reads layout version " + std::to_string(shm::kShmLayoutVersion) +
         "; use a client built for layout version " + std::to_string(attach.layout_version));
  }
  if (attach.status != 0) fail(std::string(attach.message, strnlen(attach.message, sizeof attach.message)));
  if (fd_count != 3) fail("expected 3 descriptors, got " + std::to_string(fd_count));
}

// Copies plane `index` (of channels::kPixelChannels) of `meta`, `pixels`
// pixels, into `out`; empties `out` if the frame lacks the channel. False if
// the record does not fit in the slot or disagrees with the channel table
// (sizes come from a possibly torn header).
bool CopyPlane(std::vector<uint8_t>& out, const uint8_t* slot, uint64_t slot_bytes, const shm::ShmFrameHeader& meta,
               std::size_t index, std::size_t pixels) {
  const channels::ChannelInfo& info = channels::kPixelChannels[index];
  if (!channels::Has(meta.channel_mask, info.id)) {
    out.clear();  // keeps the capacity: a reused OwnedFrame allocates nothing
    return true;
  }
  const shm::ShmChannel& record = meta.channels[index];
  const uint64_t bytes = pixels * info.bytes_per_pixel;
  if (record.channel != static_cast<uint32_t>(info.id) || record.bytes_per_pixel != info.bytes_per_pixel ||
      record.offset < shm::kShmFrameHeaderBytes || record.offset + bytes > slot_bytes) {
    return false;
  }
  out.resize(bytes);
  std::memcpy(out.data(), slot + record.offset, std::min<uint64_t>(record.bytes, bytes));
  return true;
}

// The abstract socket name is anyone's to take: attach only to a process of
// our own user (SO_PEERCRED of the listening end), as the daemon accepts
// only clients of its own user.
void CheckPeerIsUs(int socket, const std::string& name) {
  ucred peer{};
  socklen_t length = sizeof peer;
  if (getsockopt(socket, SOL_SOCKET, SO_PEERCRED, &peer, &length) != 0) {
    throw ShmError("cannot tell who serves " + name + " (SO_PEERCRED: " + std::strerror(errno) + ")");
  }
  if (peer.uid != getuid()) {
    throw ShmError("refusing to attach to " + name + ": the socket @" + shm::SocketPath(name).substr(1) +
                   " belongs to process " + std::to_string(peer.pid) + " of uid " + std::to_string(peer.uid) +
                   ", not to this user (uid " + std::to_string(getuid()) +
                   "); another user may be impersonating sim4cvd");
  }
}

}  // namespace

bool FrameView::has(proto::Channel channel) const { return slot_ && InMask(header_.channel_mask, channel); }

bool OwnedFrame::has(proto::Channel channel) const { return InMask(channel_mask, channel); }

std::optional<ImageView> OwnedFrame::image(proto::Channel channel) const {
  const auto index = channels::IndexOf(channel);
  if (!index || !has(channel)) return std::nullopt;
  const channels::ChannelInfo& info = channels::kPixelChannels[*index];
  if (planes[*index].size() < static_cast<std::size_t>(width) * height * info.bytes_per_pixel) return std::nullopt;
  return ImageView{planes[*index].data(), width, height, width * info.bytes_per_pixel, info.format, info.element,
                   info.components};
}

std::optional<ImageView> FrameView::image(proto::Channel channel) const {
  if (!has(channel)) return std::nullopt;  // an absent channel's record is zero: nothing to point at
  for (uint32_t i = 0; i < std::min(header_.channel_count, shm::kShmMaxChannels); ++i) {
    const shm::ShmChannel& c = header_.channels[i];
    if (c.channel != static_cast<uint32_t>(channel)) continue;
    return ImageView{slot_ + c.offset,
                     header_.width,
                     header_.height,
                     c.stride,
                     static_cast<proto::PixelFormat>(c.format),
                     static_cast<proto::ElementType>(c.element),
                     c.components};
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

ShmClient::~ShmClient() { Close(); }

void ShmClient::Open(const std::string& name) {
  Close();
  name_ = !name.empty() && name[0] == '/' ? name : "/" + name;
  try {
    Attach();
  } catch (...) {
    Close();
    throw;
  }
}

void ShmClient::Attach() {
  Detach();
  if (name_.size() > shm::kShmMaxNameBytes) {
    throw ShmError("shared-memory name " + name_ + " is longer than " + std::to_string(shm::kShmMaxNameBytes) +
                   " bytes: no daemon can serve it");
  }
  const std::string path = shm::SocketPath(name_);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.data(), path.size());
  socket_ = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
  if (socket_ < 0) throw ShmError(std::string("socket: ") + std::strerror(errno));
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
  if (connect(socket_, reinterpret_cast<const sockaddr*>(&address), length) != 0) {
    const int error = errno;
    throw ShmError("no sim4cvd serves shared memory under " + name_ + " (" + std::strerror(error) +
                   "); is it running with --shm-name " + name_.substr(1) + "?");
  }
  CheckPeerIsUs(socket_, name_);
  const timeval limit{5, 0};  // a daemon answers at once; a stuck one must not hang Open
  setsockopt(socket_, SOL_SOCKET, SO_RCVTIMEO, &limit, sizeof limit);
  shm::ShmAttach attach{};
  int fds[3] = {-1, -1, -1};
  int count = 0;
  ReceiveAttach(socket_, attach, fds, count, name_);
  area_fd_ = fds[1];
  doorbell_ = fds[2];
  if (frames_) {
    close(fds[0]);  // attached again: keep the frame mapping that views may point into
  } else {
    MapFrames(fds[0], attach.frames_bytes);
  }
  struct stat info {};
  if (fstat(area_fd_, &info) != 0 || static_cast<uint64_t>(info.st_size) != shm::kAreaBytes) {
    throw ShmError("the client area of " + name_ + " is " + std::to_string(info.st_size) + " bytes, not " +
                   std::to_string(shm::kAreaBytes));
  }
  void* area = mmap(nullptr, shm::kAreaBytes, PROT_READ | PROT_WRITE, MAP_SHARED, area_fd_, 0);
  if (area == MAP_FAILED) throw ShmError("cannot map the client area of " + name_ + ": " + std::strerror(errno));
  area_ = static_cast<uint8_t*>(area);
  CheckArea(shm::AreaMap(area_).header(), name_);
  next_request_ = 0;
  next_response_ = 0;
}

void ShmClient::MapFrames(int fd, uint64_t bytes) {
  frames_fd_ = fd;
  struct stat info {};
  const auto size = fstat(fd, &info) == 0 ? static_cast<std::size_t>(info.st_size) : 0;
  if (size < sizeof(shm::ShmHeader) || (bytes != 0 && size != bytes)) {
    throw ShmError("the shared-memory frame object of " + name_ + " is " + std::to_string(size) + " bytes" +
                   (bytes != 0 ? ", not the " + std::to_string(bytes) + " announced" : std::string()));
  }
  // Read-only: the daemon sealed the object against writable mappings.
  void* base = mmap(nullptr, size, PROT_READ, MAP_SHARED, fd, 0);
  if (base == MAP_FAILED) throw ShmError("cannot map the frame object of " + name_ + ": " + std::strerror(errno));
  frames_ = static_cast<uint8_t*>(base);
  geometry_.total_bytes = size;  // what to unmap, until checked
  std::atomic_thread_fence(std::memory_order_acquire);  // the magic is written last
  const shm::Geometry g = CheckFrames(header(), size, name_);
  geometry_ = g;
  geometry_.total_bytes = size;
}

void ShmClient::OpenFrames(int frames_fd) {
  Close();
  name_ = "(descriptor " + std::to_string(frames_fd) + ")";
  const int fd = fcntl(frames_fd, F_DUPFD_CLOEXEC, 0);
  if (fd < 0) throw ShmError("cannot duplicate descriptor " + std::to_string(frames_fd) + ": " + std::strerror(errno));
  try {
    MapFrames(fd, 0);
  } catch (...) {
    Close();
    throw;
  }
}

void ShmClient::Detach() {
  if (area_) munmap(area_, shm::kAreaBytes);
  area_ = nullptr;
  for (int* fd : {&area_fd_, &socket_, &doorbell_}) {
    if (*fd >= 0) close(*fd);
    *fd = -1;
  }
  pending_.clear();
}

void ShmClient::Close() {
  Detach();
  if (frames_) munmap(frames_, geometry_.total_bytes);
  frames_ = nullptr;
  if (frames_fd_ >= 0) close(frames_fd_);
  frames_fd_ = -1;
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
  if (!frames_) throw ShmError("ShmClient::Open must succeed before reading frames");
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
  const shm::FrameMap map(frames_, geometry_);
  shm::ShmHeader& h = map.header();
  for (;;) {
    const uint64_t published = shm::Atomic(h.published).load(std::memory_order_acquire);
    if (published == 0) return false;
    const uint64_t slot = (published - 1) % geometry_.slot_count;
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
  const shm::FrameMap map(frames_, geometry_);
  shm::ShmHeader& h = map.header();
  shm::ShmFrameHeader meta;
  for (;;) {
    const uint64_t published = shm::Atomic(h.published).load(std::memory_order_acquire);
    if (published == 0) return false;
    const uint64_t slot_index = (published - 1) % geometry_.slot_count;
    const uint8_t* slot = map.slot_bytes(slot_index);
    shm::ShmFrameHeader& frame = map.slot(slot_index);
    const uint64_t before = shm::Atomic(frame.sequence).load(std::memory_order_acquire);
    if (before & 1) continue;
    std::memcpy(&meta, &frame, kFrameHeaderCopyBytes);
    // Sizes come from a possibly torn header: bound them by the slot before copying.
    const std::size_t pixels =
        static_cast<std::size_t>(std::min(meta.width, h.camera_width)) * std::min(meta.height, h.camera_height);
    bool sane = meta.channel_count == channels::kPixelChannelCount;
    for (std::size_t i = 0; sane && i < channels::kPixelChannelCount; ++i) {
      sane = CopyPlane(out.planes[i], slot, geometry_.slot_bytes, meta, i, pixels);
    }
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
  for (;;) {
    const uint32_t seen = futex.load(std::memory_order_seq_cst);
    if (newest_frame_id() > after_frame_id) return true;
    if (closed()) throw ConnectionError("sim4cvd stopped: the shared-memory ring " + name_ + " is closed");
    const auto now = std::chrono::steady_clock::now();
    if (now >= deadline) return false;
    if (now < spin_end) continue;
    // The daemon wakes every waiter after each frame; FUTEX_WAIT returns at
    // once if the word moved since `seen` (works on a read-only mapping).
    shm::FutexWait(h.frame_futex, seen, std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - now).count());
  }
}

}  // namespace sim4cv
