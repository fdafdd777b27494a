#include "server/common/beneath.h"

#include <fcntl.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <vector>

namespace sim4cv {
namespace {

// The parts of a relative name; false for an empty part, ".", ".." or a
// leading '/', none of which a confined name may hold.
bool Parts(const std::string& relative, std::vector<std::string>& parts) {
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = relative.find('/', start);
    std::string part = relative.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (part.empty() || part == "." || part == "..") return false;
    parts.push_back(std::move(part));
    if (end == std::string::npos) return true;
    start = end + 1;
  }
}

// -1 when the kernel has no openat2 (ENOSYS) or refuses its use (EPERM
// under some seccomp filters): the caller walks instead.
int OpenAt2(int folder, const std::string& relative, int flags, mode_t mode, bool& unsupported) {
#ifdef SYS_openat2
  open_how how{};
  how.flags = static_cast<uint64_t>(flags);
  how.mode = (flags & (O_CREAT | O_TMPFILE)) ? mode : 0;
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS | RESOLVE_NO_MAGICLINKS;
  for (;;) {
    const long fd = ::syscall(SYS_openat2, folder, relative.c_str(), &how, sizeof how);
    if (fd >= 0) return static_cast<int>(fd);
    if (errno == EINTR || errno == EAGAIN) continue;  // EAGAIN: a rename raced the lookup; look again
    unsupported = errno == ENOSYS || errno == EPERM;
    return -1;
  }
#else
  (void)folder, (void)relative, (void)flags, (void)mode;
  unsupported = true;
  return -1;
#endif
}

// The folder `part` of `at`, never through a link: the name is opened as
// itself (O_PATH | O_NOFOLLOW), what it is read from that descriptor, and
// only a folder reopened for reading, so a link swapped in at any moment
// gives ELOOP, a file ENOTDIR.
int OpenFolderPart(int at, const char* part) {
  const int path = ::openat(at, part, O_PATH | O_NOFOLLOW | O_CLOEXEC);
  if (path < 0) return -1;
  struct stat info {};
  int fd = -1;
  if (::fstat(path, &info) != 0) {
    // errno from fstat
  } else if (S_ISLNK(info.st_mode)) {
    errno = ELOOP;
  } else if (!S_ISDIR(info.st_mode)) {
    errno = ENOTDIR;
  } else {
    fd = ::openat(path, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  }
  const int error = errno;
  ::close(path);
  errno = error;
  return fd;
}

}  // namespace

Fd& Fd::operator=(Fd&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

Fd::~Fd() {
  if (fd_ >= 0) ::close(fd_);
}

int OpenBeneathByWalk(int folder, const std::string& relative, int flags, mode_t mode) {
  std::vector<std::string> parts;
  if (!Parts(relative, parts)) {
    errno = EINVAL;
    return -1;
  }
  const auto [path, leaf] = SplitLeaf(relative);
  Fd at(OpenFolderBeneath(folder, path, false));
  if (!at.valid()) return -1;
  return ::openat(at.get(), leaf.c_str(), flags | O_NOFOLLOW | O_CLOEXEC, mode);
}

int OpenBeneath(int folder, const std::string& relative, int flags, mode_t mode) {
  std::vector<std::string> parts;
  if (!Parts(relative, parts)) {
    errno = EINVAL;
    return -1;
  }
  bool unsupported = false;
  const int fd = OpenAt2(folder, relative, flags | O_NOFOLLOW | O_CLOEXEC, mode, unsupported);
  if (fd >= 0 || !unsupported) return fd;
  return OpenBeneathByWalk(folder, relative, flags, mode);
}

int OpenFolderBeneath(int folder, const std::string& relative, bool create) {
  if (relative.empty()) return ::fcntl(folder, F_DUPFD_CLOEXEC, 0);
  std::vector<std::string> parts;
  if (!Parts(relative, parts)) {
    errno = EINVAL;
    return -1;
  }
  Fd at(::fcntl(folder, F_DUPFD_CLOEXEC, 0));
  if (!at.valid()) return -1;
  for (const std::string& part : parts) {
    Fd next(OpenFolderPart(at.get(), part.c_str()));
    if (!next.valid() && errno == ENOENT && create) {
      if (::mkdirat(at.get(), part.c_str(), 0755) != 0 && errno != EEXIST) return -1;
      next = Fd(OpenFolderPart(at.get(), part.c_str()));
    }
    if (!next.valid()) return -1;
    at = std::move(next);
  }
  return at.release();
}

std::pair<std::string, std::string> SplitLeaf(const std::string& relative) {
  const std::size_t slash = relative.rfind('/');
  if (slash == std::string::npos) return {std::string(), relative};
  return {relative.substr(0, slash), relative.substr(slash + 1)};
}

}  // namespace sim4cv
