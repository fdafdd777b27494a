// Where shared-memory clients attach: a SOCK_SEQPACKET Unix socket in the
// abstract namespace named after --shm-name (shm::SocketPath), so there is no
// file to go stale, remove or replace. Each accepted connection gets one
// ShmAttach message, with the frame object's, its own area's and its
// doorbell's descriptors (SCM_RIGHTS), or a refusal; the connection then
// stays open for as long as the client is attached (its end is how the
// daemon learns that a client died).
#pragma once

#include <string>

#include "protocol/shm_layout.h"

namespace sim4cv::transport {

class ShmListener {
 public:
  // Binds and listens. Throws std::invalid_argument for a name that does not
  // fit, std::runtime_error if it is taken (another daemon serves it).
  explicit ShmListener(const std::string& name);
  ~ShmListener();
  ShmListener(const ShmListener&) = delete;
  ShmListener& operator=(const ShmListener&) = delete;

  int fd() const { return fd_; }
  // A pending connection (non-blocking, close-on-exec), or -1: none pending
  // (errno EAGAIN) or accept failed (errno says why).
  int Accept() const;

  // Only processes of the daemon's own user (or root) may attach, as only
  // they could open a 0600 object before. False with `why` otherwise.
  static bool PeerAllowed(int connection, std::string& why);
  // Sends `attach` with `fds` (three, or none for a refusal). False if the
  // socket refused it (the client is already gone).
  static bool Send(int connection, const shm::ShmAttach& attach, const int* fds, int fd_count);
  // Sends a refusal naming `message` (cut to fit).
  static void Refuse(int connection, const std::string& message);

 private:
  int fd_ = -1;
};

}  // namespace sim4cv::transport
