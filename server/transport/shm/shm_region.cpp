#include "server/transport/shm/shm_region.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "protocol/framing.h"
#include "server/common/log.h"

namespace sim4cv::transport {
namespace {

[[noreturn]] void Fail(const std::string& name, const std::string& what, int error) {
  throw std::runtime_error("shared-memory object " + name + ": " + what + " failed: " + std::strerror(error));
}

void CheckParams(const ShmRegionParams& p) {
  if (p.name.size() < 2 || p.name[0] != '/' || p.name.find('/', 1) != std::string::npos || p.name.size() > 200) {
    throw std::invalid_argument("shared-memory name '" + p.name +
                                "' must be '/' followed by 1 to 199 characters without '/'");
  }
  if (p.slot_count < 2)
    throw std::invalid_argument("--shm-slots " + std::to_string(p.slot_count) + " must be at least 2");
  if (p.reply_capacity < 1 || p.response_entries < 1) {
    throw std::invalid_argument("the shared-memory reply ring (" + std::to_string(p.reply_capacity) +
                                " slots) and response area (" + std::to_string(p.response_entries) +
                                " entries) need at least one each");
  }
  if (p.channel_mask == 0 || (p.channel_mask & ~shm::kShmAllPixelChannels) != 0) {
    throw std::invalid_argument("--shm-channels must name one or more of rgb, depth and mask (channel mask " +
                                std::to_string(p.channel_mask) + ")");
  }
  if (p.width == 0 || p.height == 0)
    throw std::invalid_argument("shared-memory ring for camera '" + p.camera_name + "' has size 0");
  if (p.camera_name.size() >= sizeof(shm::ShmHeader::camera_name)) {
    throw std::invalid_argument("camera name '" + p.camera_name + "' is longer than the shared-memory header's " +
                                std::to_string(sizeof(shm::ShmHeader::camera_name) - 1) + " characters");
  }
}

}  // namespace

ShmRegion::ShmRegion(const ShmRegionParams& params) : params_(params) {
  CheckParams(params_);
  geometry_ = shm::ComputeGeometry(params_.width, params_.height, params_.slot_count, params_.reply_capacity,
                                   params_.response_entries, params_.channel_mask);
  const char* name = params_.name.c_str();
  // A daemon that crashed left its object behind: replace it.
  if (shm_unlink(name) == 0) {
    LOG_INFO("replaced the stale shared-memory object " << params_.name
                                                        << " (left by a daemon that did not stop cleanly)");
  } else if (errno != ENOENT) {
    Fail(params_.name, "removing the existing object (pick another --shm-name)", errno);
  }
  const int fd = shm_open(name, O_CREAT | O_EXCL | O_RDWR, 0600);
  if (fd < 0) Fail(params_.name, "shm_open(O_CREAT|O_EXCL)", errno);
  linked_ = true;
  struct stat identity {};
  if (fstat(fd, &identity) == 0) {
    device_ = identity.st_dev;
    inode_ = identity.st_ino;
  }
  // Reserve the memory now: a full /dev/shm must fail here, not as SIGBUS on the first frame.
  const int reserve_error = posix_fallocate(fd, 0, static_cast<off_t>(geometry_.total_bytes));
  if (reserve_error != 0) {
    close(fd);
    Unlink();
    Fail(params_.name, "reserving " + std::to_string(geometry_.total_bytes) + " bytes (is /dev/shm large enough?)",
         reserve_error);
  }
  // MAP_POPULATE: no page faults on the sim thread when it first writes a slot.
  void* base = mmap(nullptr, geometry_.total_bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd, 0);
  const int map_error = errno;
  close(fd);
  if (base == MAP_FAILED) {
    Unlink();
    Fail(params_.name, "mmap of " + std::to_string(geometry_.total_bytes) + " bytes", map_error);
  }
  map_ = shm::Mapped(base);

  shm::ShmHeader& h = header();  // the new object reads as zeros
  h.layout_version = shm::kShmLayoutVersion;
  h.header_bytes = shm::kShmHeaderBytes;
  h.total_bytes = geometry_.total_bytes;
  h.slot_count = params_.slot_count;
  h.frame_header_bytes = shm::kShmFrameHeaderBytes;
  h.slot_bytes = geometry_.slot_bytes;
  h.slots_offset = geometry_.slots_offset;
  h.camera_width = params_.width;
  h.camera_height = params_.height;
  h.writer_pid = static_cast<uint32_t>(getpid());
  h.max_boxes = shm::kShmMaxBoxes;
  std::memcpy(h.camera_name, params_.camera_name.data(), params_.camera_name.size());
  h.reply_offset = geometry_.reply_offset;
  h.reply_capacity = params_.reply_capacity;
  h.reply_slot_bytes = shm::kShmReplySlotBytes;
  h.response_offset = geometry_.response_offset;
  h.response_entries = params_.response_entries;
  h.response_depth = shm::kShmResponseDepth;
  h.response_message_bytes = shm::kShmResponseMessageBytes;
  h.max_entities = shm::kShmMaxEntities;
  h.expiry_ms = params_.expiry_ms;
  h.protocol_version = wire::kProtocolVersion;
  h.response_entry_bytes = geometry_.response_entry_bytes;
  h.channel_mask = params_.channel_mask;
  // The magic goes last: a reader that sees it sees a complete header.
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(h.magic, SIM4CV_SHM_MAGIC, sizeof h.magic);
}

ShmRegion::~ShmRegion() {
  if (map_.base()) munmap(map_.base(), geometry_.total_bytes);
}

void ShmRegion::Unlink() {
  if (!linked_) return;
  linked_ = false;
  // Only our own object: another daemon may have replaced it under this name since.
  const int fd = shm_open(params_.name.c_str(), O_RDONLY, 0);
  if (fd < 0) return;
  struct stat identity {};
  const bool ours = fstat(fd, &identity) == 0 && identity.st_dev == device_ && identity.st_ino == inode_;
  close(fd);
  if (!ours) {
    LOG_INFO("left the shared-memory object " << params_.name << " in place: another daemon has replaced ours");
    return;
  }
  if (shm_unlink(params_.name.c_str()) != 0 && errno != ENOENT) {
    LOG_WARNING("could not remove the shared-memory object " << params_.name << ": " << std::strerror(errno));
  }
}

}  // namespace sim4cv::transport
