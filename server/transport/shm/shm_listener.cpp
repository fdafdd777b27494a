#include "server/transport/shm/shm_listener.h"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstring>
#include <stdexcept>

#include "protocol/shm_sync.h"

namespace sim4cv::transport {

ShmListener::ShmListener(const std::string& name) {
  if (name.size() < 2 || name[0] != '/' || name.find('/', 1) != std::string::npos ||
      name.size() > shm::kShmMaxNameBytes) {
    throw std::invalid_argument("--shm-name '" + name + "' must be '/' followed by 1 to " +
                                std::to_string(shm::kShmMaxNameBytes - 1) + " characters without '/'");
  }
  const std::string path = shm::SocketPath(name);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, path.data(), path.size());
  fd_ = socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::runtime_error("shared memory " + name + ": socket failed: " + std::strerror(errno));
  const auto length = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&address), length) != 0 || listen(fd_, 64) != 0) {
    const int error = errno;
    close(fd_);
    throw std::runtime_error(
        "shared memory " + name + ": cannot listen on the abstract Unix socket @" + path.substr(1) + ": " +
        std::strerror(error) +
        (error == EADDRINUSE ? " (another sim4cvd serves this --shm-name; pick another)" : std::string()));
  }
}

ShmListener::~ShmListener() { close(fd_); }

int ShmListener::Accept() const { return accept4(fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC); }

bool ShmListener::PeerAllowed(int connection, std::string& why) {
  ucred peer{};
  socklen_t size = sizeof peer;
  if (getsockopt(connection, SOL_SOCKET, SO_PEERCRED, &peer, &size) != 0) {
    why = std::string("its credentials are unknown: ") + std::strerror(errno);
    return false;
  }
  if (peer.uid == geteuid() || peer.uid == 0) return true;
  why = "process " + std::to_string(peer.pid) + " runs as user " + std::to_string(peer.uid) +
        "; only the daemon's own user (" + std::to_string(geteuid()) + ") or root may attach";
  return false;
}

bool ShmListener::Send(int connection, const shm::ShmAttach& attach, const int* fds, int fd_count) {
  iovec data{const_cast<shm::ShmAttach*>(&attach), sizeof attach};
  alignas(cmsghdr) char control[CMSG_SPACE(3 * sizeof(int))] = {};
  msghdr message{};
  message.msg_iov = &data;
  message.msg_iovlen = 1;
  if (fd_count > 0) {
    message.msg_control = control;
    message.msg_controllen = CMSG_SPACE(static_cast<std::size_t>(fd_count) * sizeof(int));
    cmsghdr* header = CMSG_FIRSTHDR(&message);
    header->cmsg_level = SOL_SOCKET;
    header->cmsg_type = SCM_RIGHTS;
    header->cmsg_len = CMSG_LEN(static_cast<std::size_t>(fd_count) * sizeof(int));
    std::memcpy(CMSG_DATA(header), fds, static_cast<std::size_t>(fd_count) * sizeof(int));
  }
  return sendmsg(connection, &message, MSG_NOSIGNAL | MSG_DONTWAIT) == static_cast<ssize_t>(sizeof attach);
}

void ShmListener::Refuse(int connection, const std::string& text) {
  shm::ShmAttach attach{};
  std::memcpy(attach.magic, SIM4CV_SHM_ATTACH_MAGIC, sizeof attach.magic);
  attach.layout_version = shm::kShmLayoutVersion;
  attach.status = 1;
  std::memcpy(attach.message, text.data(), std::min(text.size(), sizeof attach.message - 1));
  Send(connection, attach, nullptr, 0);
}

}  // namespace sim4cv::transport
