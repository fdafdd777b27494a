#include "server/daemon/named_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/daemon/configure_error.h"

namespace sim4cv::daemon {
namespace {

[[noreturn]] void Fail(proto::ErrorCode code, const std::string& message) { throw ConfigureError(code, message); }

std::string SystemReason(int error) { return std::strerror(error); }

// One of the folders named paths live under: its flag's value and its
// descriptor. The folder must exist (a daemon started with a --maps-dir
// that does not is told so, not given a new folder); the operator's path
// itself may pass through links.
struct Root {
  Root(const std::string& dir_, const char* what, const char* flag_, std::string field_)
      : dir(dir_), flag(flag_), field(std::move(field_)) {
    fd = Fd(::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
    if (!fd.valid()) {
      Fail(proto::ERROR_CODE_IO, std::string("the ") + what + " " + Quoted(dir) + " (sim4cvd " + flag +
                                     ") is not a folder; start sim4cvd with " + flag + " naming one");
    }
  }
  std::string Shown(const std::string& relative) const { return dir + (dir.back() == '/' ? "" : "/") + relative; }

  std::string dir;
  const char* flag;
  std::string field;  // the request's field, e.g. "OpenMap.name 'x'", that Errors start with
  Fd fd;
};

// The Error for an open beneath `root` that failed with `error`; ENOENT is
// the caller's to word.
[[noreturn]] void FailOpen(const Root& root, const std::string& relative, int error) {
  const std::string shown = root.field + ": " + Quoted(root.Shown(relative));
  if (error == ELOOP || error == EXDEV) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, shown + " is a symbolic link or passes through one; sim4cvd reads and "
                                                 "writes only real files and folders under " +
                                                 root.flag);
  }
  if (error == ENOTDIR) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, shown + ": a part of it is a file, not a folder: choose another name");
  }
  if (error == EINVAL) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, shown + " is not a name beneath " + root.flag +
                                                 ": give '/'-separated parts, none empty, '.' or '..'");
  }
  if (error == ENAMETOOLONG) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, shown + ": a part of the name is too long; give at most " +
                                                 std::to_string(limits::kMaxFileNamePartBytes) + " bytes a part");
  }
  Fail(proto::ERROR_CODE_IO, "cannot open " + shown + ": " + SystemReason(error));
}

// The folder of `relative` (created when `create`), refused as FailOpen says.
Fd FolderOf(const Root& root, const std::string& relative, bool create) {
  const std::string folder = SplitLeaf(relative).first;
  Fd fd(OpenFolderBeneath(root.fd.get(), folder, create));
  if (!fd.valid()) FailOpen(root, folder, errno);
  return fd;
}

// A file about to be written in `folder`: an existing one only with
// `overwrite`, and only a regular file. Returns whether it exists.
bool RefuseExisting(int folder, const std::string& leaf, const std::string& shown, bool overwrite,
                    const char* request, const char* flag) {
  struct stat info {};
  if (::fstatat(folder, leaf.c_str(), &info, AT_SYMLINK_NOFOLLOW) != 0) return false;
  if (S_ISLNK(info.st_mode)) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT,
         Quoted(shown) + " is a symbolic link; sim4cvd reads and writes only real files and folders under " + flag);
  }
  if (!overwrite) {
    Fail(proto::ERROR_CODE_ALREADY_EXISTS,
         std::string(request) + ": " + Quoted(shown) + " exists; set overwrite to replace it, or choose another name");
  }
  if (!S_ISREG(info.st_mode)) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, Quoted(shown) + " is not a regular file: choose another name");
  }
  return true;
}

// write(2) until done; false with errno set on a failure.
bool WriteAll(int fd, const std::string& text) {
  for (std::size_t done = 0; done < text.size();) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// ListMapNames' walk: from the folder's descriptor, every part opened with
// O_NOFOLLOW, so a link swapped in is skipped, not entered.
class MapWalk {
 public:
  void Walk(int folder, const std::string& prefix, int depth) {
    const int listed = ::openat(folder, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (listed < 0) return;
    DIR* dir = ::fdopendir(listed);
    if (dir == nullptr) {
      ::close(listed);
      return;
    }
    // The walk is bounded too: a --maps-dir pointed at a huge tree costs at
    // most this many entries.
    constexpr std::size_t kMaxEntriesWalked = 20 * limits::kMaxListedMaps;
    while (const dirent* entry = ::readdir(dir)) {
      if (++walked_ > kMaxEntriesWalked) break;
      const std::string name = entry->d_name;
      if (name.empty() || name.front() == '.') continue;  // ".", ".." and hidden files no request can name
      struct stat info {};
      if (::fstatat(::dirfd(dir), name.c_str(), &info, AT_SYMLINK_NOFOLLOW) != 0) continue;
      if (S_ISDIR(info.st_mode) && depth < limits::kMaxListedMapDepth) {
        Fd sub(::openat(::dirfd(dir), name.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
        if (sub.valid()) Walk(sub.get(), prefix + name + "/", depth + 1);
      } else if (S_ISREG(info.st_mode) && name.size() > 4 && name.compare(name.size() - 4, 4, ".map") == 0) {
        found_.push_back(prefix + name.substr(0, name.size() - 4));
      }
    }
    ::closedir(dir);
  }
  std::vector<std::string>& found() { return found_; }

 private:
  std::size_t walked_ = 0;
  std::vector<std::string> found_;
};

// SaveMap's quota: refuses `adding` more bytes in `folder` (replacing
// `leaf`, if it exists) past limits::kMaxMapsPerFolder files or
// limits::kMaxMapFolderBytes bytes of maps.
void CheckQuota(int folder, const std::string& leaf, std::size_t adding, const std::string& shown_folder) {
  const int listed = ::openat(folder, ".", O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  DIR* dir = listed < 0 ? nullptr : ::fdopendir(listed);
  if (dir == nullptr) {
    if (listed >= 0) ::close(listed);
    return;
  }
  std::size_t count = 1;
  std::uint64_t bytes = adding;
  while (const dirent* entry = ::readdir(dir)) {
    const std::string name = entry->d_name;
    struct stat info {};
    if (name == leaf || name.size() < 5 || name.compare(name.size() - 4, 4, ".map") != 0 ||
        ::fstatat(::dirfd(dir), name.c_str(), &info, AT_SYMLINK_NOFOLLOW) != 0 || !S_ISREG(info.st_mode)) {
      continue;
    }
    ++count;
    bytes += static_cast<std::uint64_t>(info.st_size);
  }
  ::closedir(dir);
  if (count > limits::kMaxMapsPerFolder || bytes > limits::kMaxMapFolderBytes) {
    Fail(proto::ERROR_CODE_IO, "SaveMap: the folder " + Quoted(shown_folder) + " would hold " + std::to_string(count) +
                                   " maps of " + std::to_string(bytes) + " bytes; a folder holds at most " +
                                   std::to_string(limits::kMaxMapsPerFolder) + " maps and " +
                                   std::to_string(limits::kMaxMapFolderBytes) +
                                   " bytes (limits::kMaxMapsPerFolder, kMaxMapFolderBytes): remove some, or save "
                                   "into another folder");
  }
}

}  // namespace

void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names) {
  const Fd root(::open(maps_dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (!root.valid()) return;
  MapWalk walk;
  walk.Walk(root.get(), "", 0);
  std::vector<std::string>& found = walk.found();
  std::sort(found.begin(), found.end());
  if (found.size() > limits::kMaxListedMaps) found.resize(limits::kMaxListedMaps);
  for (std::string& name : found) names.Add(std::move(name));
}

std::string ReadMapFile(const std::string& maps_dir, const std::string& name, const char* field) {
  const Root root(maps_dir, "maps folder", "--maps-dir", std::string(field) + " " + Quoted(name));
  const std::string relative = name + ".map";
  // O_NONBLOCK: a FIFO put there must not block the thread.
  const Fd fd(OpenBeneath(root.fd.get(), relative, O_RDONLY | O_NONBLOCK));
  if (!fd.valid()) {
    if (errno == ENOENT) {
      Fail(proto::ERROR_CODE_INVALID_ARGUMENT, std::string(field) + " " + Quoted(name) + ": no such map (looked for " +
                                                   root.Shown(relative) + "); ListMaps names them");
    }
    FailOpen(root, relative, errno);
  }
  struct stat info {};
  if (::fstat(fd.get(), &info) != 0 || !S_ISREG(info.st_mode)) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT,
         std::string(field) + " " + Quoted(name) + ": " + Quoted(root.Shown(relative)) + " is not a regular file");
  }
  if (static_cast<std::size_t>(info.st_size) > limits::kMaxMapTextBytes) {
    Fail(proto::ERROR_CODE_IO, Quoted(root.Shown(relative)) + " is " + std::to_string(info.st_size) +
                                   " bytes; a map has at most " + std::to_string(limits::kMaxMapTextBytes));
  }
  std::string text;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) Fail(proto::ERROR_CODE_IO, "cannot read " + Quoted(root.Shown(relative)) + ": " + SystemReason(errno));
    if (n == 0) return text;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > limits::kMaxMapTextBytes) {
      Fail(proto::ERROR_CODE_IO, Quoted(root.Shown(relative)) + " grew past " +
                                     std::to_string(limits::kMaxMapTextBytes) + " bytes while read");
    }
  }
}

void WriteMapFile(const std::string& maps_dir, const std::string& name, const std::string& text, bool overwrite) {
  const Root root(maps_dir, "maps folder", "--maps-dir", "SaveMap.name " + Quoted(name));
  const std::string relative = name + ".map";
  const Fd folder = FolderOf(root, relative, true);
  const std::string leaf = SplitLeaf(relative).second;
  const std::string shown = root.Shown(relative);
  RefuseExisting(folder.get(), leaf, shown, overwrite, "SaveMap", root.flag);
  CheckQuota(folder.get(), leaf, text.size(), root.Shown(SplitLeaf(relative).first));
  // Beside the target, so the rename stays on one file system; the pid keeps
  // two daemons sharing a folder apart, O_EXCL a stale leftover.
  std::string hidden = leaf;  // built step by step: GCC 12 warns (-Wrestrict) on "." + ...
  hidden.insert(0, 1, '.');
  hidden += ".tmp";
  hidden += std::to_string(::getpid());
  ::unlinkat(folder.get(), hidden.c_str(), 0);
  const int fd = ::openat(folder.get(), hidden.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) FailOpen(root, relative, errno);
  const bool written = WriteAll(fd, text) && ::fsync(fd) == 0;
  const int write_error = errno;
  ::close(fd);
  // The rename replaces a link at the leaf rather than following it; without
  // overwrite it never replaces anything (a file made since the check is kept).
  const bool renamed =
      written && ::renameat2(folder.get(), hidden.c_str(), folder.get(), leaf.c_str(), overwrite ? 0 : RENAME_NOREPLACE) == 0;
  if (!renamed) {
    const int reason = written ? errno : write_error;
    ::unlinkat(folder.get(), hidden.c_str(), 0);
    if (reason == EEXIST) RefuseExisting(folder.get(), leaf, shown, false, "SaveMap", root.flag);
    Fail(proto::ERROR_CODE_IO,
         "cannot write " + Quoted(shown) + ": " + SystemReason(reason) + "; the file on disk is unchanged");
  }
}

void NewLogFile::Discard() {
  fd = Fd();
  if (folder.valid()) ::unlinkat(folder.get(), leaf.c_str(), 0);
}

NewLogFile CreateLogFile(const std::string& logs_dir, const std::string& name, bool overwrite) {
  if (logs_dir.empty()) {
    Fail(proto::ERROR_CODE_INVALID_STATE,
         "StartLog: sim4cvd was started without --logs-dir, so clients cannot write run logs; start it with "
         "--logs-dir DIR (or record the whole run with --log FILE)");
  }
  const Root root(logs_dir, "logs folder", "--logs-dir", "StartLog.name " + Quoted(name));
  const std::string relative = name + ".s4log";
  NewLogFile log;
  log.folder = FolderOf(root, relative, true);
  log.leaf = SplitLeaf(relative).second;
  log.path = root.Shown(relative);
  // Replaced by a new file, never truncated: a hard link there to a file
  // elsewhere keeps its content.
  if (RefuseExisting(log.folder.get(), log.leaf, log.path, overwrite, "StartLog", root.flag)) {
    ::unlinkat(log.folder.get(), log.leaf.c_str(), 0);
  }
  log.fd = Fd(::openat(log.folder.get(), log.leaf.c_str(),
                       O_WRONLY | O_CREAT | O_EXCL | O_APPEND | O_NOFOLLOW | O_CLOEXEC, 0644));
  if (!log.fd.valid()) {
    const int error = errno;
    if (error == EEXIST) RefuseExisting(log.folder.get(), log.leaf, log.path, false, "StartLog", root.flag);
    FailOpen(root, relative, error);
  }
  return log;
}

}  // namespace sim4cv::daemon
