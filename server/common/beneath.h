// Opening files a client names only beneath their folder. Checking a path
// and then opening it by name leaves a window in which another local user
// can swap a symbolic link into it; so every open here starts from the
// folder's descriptor and refuses a link in any part of the name at the
// moment of opening: openat2(RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS) where
// the kernel has it (Linux 5.6), else a walk of openat(O_NOFOLLOW) calls,
// one part at a time from the folder's descriptor.
#pragma once

#include <sys/types.h>

#include <string>
#include <utility>

namespace sim4cv {

// A file descriptor that closes itself.
class Fd {
 public:
  Fd() = default;
  explicit Fd(int fd) : fd_(fd) {}
  Fd(Fd&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  Fd& operator=(Fd&& other) noexcept;
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  ~Fd();

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_ = -1;
};

// open(relative, flags, mode) beneath the folder `folder` (a descriptor):
// `relative` is '/'-separated parts, none empty, "." or ".."; no part may be
// a symbolic link (ELOOP). O_CLOEXEC and O_NOFOLLOW are always added. -1
// with errno set on failure, as open(2).
int OpenBeneath(int folder, const std::string& relative, int flags, mode_t mode = 0);

// The same by walking the parts with openat(O_NOFOLLOW | O_DIRECTORY): what
// OpenBeneath falls back to without openat2 (public so tests can run it on
// any kernel).
int OpenBeneathByWalk(int folder, const std::string& relative, int flags, mode_t mode = 0);

// The folder `relative` beneath `folder` as a descriptor, each missing part
// made (mode 0755) when `create`; -1 with errno on failure (ELOOP for a
// symbolic link, ENOTDIR for a file where a folder belongs).
int OpenFolderBeneath(int folder, const std::string& relative, bool create);

// Splits "a/b/c.map" into its folder "a/b" ("" for none) and leaf "c.map".
std::pair<std::string, std::string> SplitLeaf(const std::string& relative);

}  // namespace sim4cv
