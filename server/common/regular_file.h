// Opening the files the daemon is named on its command line (--map, --scene,
// --replay, --log) or finds in --maps-dir, without ever blocking. By the
// time they are opened SIGINT and SIGTERM are blocked for sigwait, so an
// open() that blocks (a FIFO with no one at its other end) would hang the
// start beyond SIGTERM's reach (docs/reliability.md, finding 7). Every such file is
// opened with O_NONBLOCK and refused unless it is a regular file; the
// descriptor returned blocks again, as an ordinary file's does.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>

namespace sim4cv {

// "a FIFO (named pipe)", "a directory", ... for a file that is not regular.
inline const char* FileKindName(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

inline std::string NotRegularMessage(const std::string& what, const std::string& path, mode_t mode) {
  return what + " '" + path + "' is " + FileKindName(mode) +
         ", not a regular file; sim4cvd reads and writes only regular files (a pipe or device could block it)";
}

// Which files are accepted: regular ones only, or (for a file only written,
// such as a run log) character devices too: /dev/null discards a log,
// /dev/full tests a full disk, and neither blocks.
enum class FileKinds { kRegular, kRegularOrCharacterDevice };

inline bool Accepted(mode_t mode, FileKinds kinds) {
  return S_ISREG(mode) || (kinds == FileKinds::kRegularOrCharacterDevice && S_ISCHR(mode));
}

// open(path, flags, mode) that never blocks and gives a descriptor only for
// a file of `kinds`; otherwise std::invalid_argument, its message starting
// with `what` ("map file", "run log"). A failed open throws
// std::system_error with its errno, naming `what` and the path.
inline int OpenRegularFile(const std::string& path, int flags, const std::string& what,
                           FileKinds kinds = FileKinds::kRegular, mode_t mode = 0644) {
  // A FIFO opened for writing with O_NONBLOCK and no reader fails with
  // ENXIO, which says nothing useful: name what it is first.
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && !Accepted(info.st_mode, kinds)) {
    throw std::invalid_argument(NotRegularMessage(what, path, info.st_mode));
  }
  const int fd = ::open(path.c_str(), flags | O_NONBLOCK | O_CLOEXEC, mode);
  if (fd < 0) throw std::system_error(errno, std::generic_category(), "cannot open " + what + " '" + path + "'");
  // Checked again on what was opened: the path may have changed since stat.
  if (::fstat(fd, &info) != 0 || !Accepted(info.st_mode, kinds)) {
    ::close(fd);
    throw std::invalid_argument(NotRegularMessage(what, path, info.st_mode));
  }
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  return fd;
}

// The whole of a regular file, read through OpenRegularFile; over
// `max_bytes` bytes it is refused, naming `limit` (e.g.
// "limits::kMaxMapTextBytes").
inline std::string ReadRegularFile(const std::string& path, const std::string& what, std::size_t max_bytes,
                                   const char* limit) {
  int fd = -1;
  try {
    fd = OpenRegularFile(path, O_RDONLY, what);
  } catch (const std::system_error& error) {
    throw std::invalid_argument(error.what());  // what the text parsers' callers expect
  }
  std::string text;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int error = errno;
      ::close(fd);
      throw std::invalid_argument("cannot read " + what + " '" + path + "': " + std::strerror(error));
    }
    if (n == 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > max_bytes) {
      ::close(fd);
      throw std::invalid_argument(what + " '" + path + "' is larger than " + std::to_string(max_bytes) + " bytes (" +
                                  limit + ")");
    }
  }
  ::close(fd);
  return text;
}

}  // namespace sim4cv
