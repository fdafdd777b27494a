#include "server/transport/shm/shm_region.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "protocol/framing.h"

namespace sim4cv::transport {
namespace {

[[noreturn]] void Fail(const std::string& what, const std::string& call, int error) {
  throw std::runtime_error("shared memory (" + what + "): " + call + " failed: " + std::strerror(error));
}

void CheckParams(const ShmRegionParams& p) {
  if (p.slot_count < 2)
    throw std::invalid_argument("--shm-slots " + std::to_string(p.slot_count) + " must be at least 2");
  if (p.channel_mask == 0 || (p.channel_mask & ~channels::kAllPixels) != 0) {
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

void* CreateSealableMemory(const char* what, uint64_t bytes, int& fd) {
  fd = memfd_create(what, MFD_CLOEXEC | MFD_ALLOW_SEALING);
  if (fd < 0) Fail(what, "memfd_create", errno);
  int error = ftruncate(fd, static_cast<off_t>(bytes)) == 0 ? 0 : errno;
  if (error == 0) error = posix_fallocate(fd, 0, static_cast<off_t>(bytes));
  void* base = error == 0 ? mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd, 0) : nullptr;
  if (error == 0 && base == MAP_FAILED) error = errno;
  if (error != 0) {
    close(fd);
    fd = -1;
    Fail(what, "reserving and mapping " + std::to_string(bytes) + " bytes", error);
  }
  return base;
}

void Seal(const char* what, int fd, int seals) {
  if (fcntl(fd, F_ADD_SEALS, seals) != 0) Fail(what, "sealing (F_ADD_SEALS)", errno);
}

ShmRegion::ShmRegion(const ShmRegionParams& params) : params_(params) {
  CheckParams(params_);
  const shm::Geometry g = shm::ComputeGeometry(params_.width, params_.height, params_.slot_count, params_.channel_mask);
  void* base = CreateSealableMemory("sim4cv-frames", g.total_bytes, fd_);
  map_ = shm::FrameMap(base, g);
  try {
    // No one else may shrink it (SIGBUS on the next frame), grow it, or map it writable.
    Seal("sim4cv-frames", fd_, F_SEAL_SHRINK | F_SEAL_GROW | F_SEAL_FUTURE_WRITE | F_SEAL_SEAL);
  } catch (...) {
    munmap(base, g.total_bytes);
    close(fd_);
    throw;
  }

  shm::ShmHeader& h = header();  // the new object reads as zeros
  h.layout_version = shm::kShmLayoutVersion;
  h.header_bytes = shm::kShmHeaderBytes;
  h.total_bytes = g.total_bytes;
  h.slot_count = params_.slot_count;
  h.frame_header_bytes = shm::kShmFrameHeaderBytes;
  h.slot_bytes = g.slot_bytes;
  h.slots_offset = g.slots_offset;
  h.camera_width = params_.width;
  h.camera_height = params_.height;
  h.writer_pid = static_cast<uint32_t>(getpid());
  h.max_boxes = shm::kShmMaxBoxes;
  std::memcpy(h.camera_name, params_.camera_name.data(), params_.camera_name.size());
  h.max_entities = shm::kShmMaxEntities;
  h.expiry_ms = params_.expiry_ms;
  h.protocol_version = wire::kProtocolVersion;
  h.channel_mask = params_.channel_mask;
  // The magic goes last: a reader that sees it sees a complete header.
  std::atomic_thread_fence(std::memory_order_release);
  std::memcpy(h.magic, SIM4CV_SHM_MAGIC, sizeof h.magic);
}

ShmRegion::~ShmRegion() {
  munmap(map_.base(), map_.geometry().total_bytes);
  close(fd_);
}

}  // namespace sim4cv::transport
