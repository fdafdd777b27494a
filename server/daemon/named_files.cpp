#include "server/daemon/named_files.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/daemon/configure_error.h"

namespace sim4cv::daemon {
namespace fs = std::filesystem;
namespace {

[[noreturn]] void Fail(proto::ErrorCode code, const std::string& message) { throw ConfigureError(code, message); }

std::string SystemReason(int error) { return std::strerror(error); }

// The folder named paths live under; it must exist (a daemon started with a
// --maps-dir that does not is told so, not given a new folder).
fs::path Root(const std::string& dir, const char* what, const char* flag) {
  std::error_code error;
  if (!fs::is_directory(dir, error)) {
    Fail(proto::ERROR_CODE_IO, std::string("the ") + what + " " + Quoted(dir) + " (sim4cvd " + flag +
                                   ") is not a folder; start sim4cvd with " + flag + " naming one");
  }
  return fs::path(dir);
}

// Walks `name`'s folders under `root`, refusing a symbolic link or a file
// where a folder belongs (creating missing folders when `create`); returns
// the map file's path.
fs::path Confined(const fs::path& root, const std::string& name, const char* extension, bool create) {
  fs::path at = root;
  const fs::path relative(name + extension);
  for (auto part = relative.begin(); part != relative.end(); ++part) {
    at /= *part;
    const bool last = std::next(part) == relative.end();
    std::error_code error;
    const fs::file_status status = fs::symlink_status(at, error);
    if (fs::is_symlink(status)) {
      Fail(proto::ERROR_CODE_INVALID_ARGUMENT, Quoted(at.string()) +
                                                   " is a symbolic link; the studio reads and writes only real files "
                                                   "and folders under --maps-dir");
    }
    if (last) break;
    if (!fs::exists(status)) {
      if (!create) break;  // the file cannot exist either; the caller says so
      if (!fs::create_directory(at, error) && error) {
        Fail(proto::ERROR_CODE_IO, "cannot create the folder " + Quoted(at.string()) + ": " + error.message());
      }
    } else if (!fs::is_directory(status)) {
      Fail(proto::ERROR_CODE_INVALID_ARGUMENT, Quoted(at.string()) + " is a file, not a folder: choose another name");
    }
  }
  return root / relative;
}

// A file about to be written: an existing one only with `overwrite`, and
// only a regular file.
void RefuseExisting(const fs::path& path, bool overwrite, const char* request) {
  std::error_code error;
  if (!fs::exists(path, error)) return;
  if (!overwrite) {
    Fail(proto::ERROR_CODE_ALREADY_EXISTS, std::string(request) + ": " + Quoted(path.string()) +
                                               " exists; set overwrite to replace it, or choose another name");
  }
  if (!fs::is_regular_file(path, error)) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT, Quoted(path.string()) + " is not a regular file: choose another name");
  }
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

}  // namespace

void ListMapNames(const std::string& maps_dir, google::protobuf::RepeatedPtrField<std::string>& names) {
  // The walk is bounded too: a --maps-dir pointed at a huge tree costs the
  // sim thread (every client's frames wait) at most this many entries.
  constexpr std::size_t kMaxEntriesWalked = 20 * limits::kMaxListedMaps;
  std::vector<std::string> found;
  std::error_code error;
  const fs::path root(maps_dir);
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, error);
  std::size_t walked = 0;
  for (; !error && it != fs::recursive_directory_iterator() && walked < kMaxEntriesWalked; it.increment(error)) {
    ++walked;
    const fs::directory_entry& entry = *it;
    std::error_code status_error;
    if (entry.path().extension() != ".map" || !entry.is_regular_file(status_error) || entry.is_symlink(status_error)) {
      continue;
    }
    fs::path relative = entry.path().lexically_relative(root);
    relative.replace_extension();
    found.push_back(relative.generic_string());
  }
  std::sort(found.begin(), found.end());
  if (found.size() > limits::kMaxListedMaps) found.resize(limits::kMaxListedMaps);
  for (std::string& name : found) names.Add(std::move(name));
}

std::string ReadMapFile(const std::string& maps_dir, const std::string& name) {
  const fs::path path = Confined(Root(maps_dir, "maps folder", "--maps-dir"), name, ".map", false);
  std::error_code error;
  if (!fs::is_regular_file(path, error)) {
    Fail(proto::ERROR_CODE_INVALID_ARGUMENT,
         "OpenMap.name " + Quoted(name) + ": no such map (looked for " + path.string() + "); ListMaps names them");
  }
  const auto size = fs::file_size(path, error);
  if (error || size > limits::kMaxMapTextBytes) {
    Fail(proto::ERROR_CODE_IO,
         Quoted(path.string()) + (error ? ": " + error.message()
                                        : " is " + std::to_string(size) + " bytes; a map has at most " +
                                              std::to_string(limits::kMaxMapTextBytes)));
  }
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) Fail(proto::ERROR_CODE_IO, "cannot read " + Quoted(path.string()) + ": " + SystemReason(errno));
  return text.str();
}

void WriteMapFile(const std::string& maps_dir, const std::string& name, const std::string& text, bool overwrite) {
  const fs::path path = Confined(Root(maps_dir, "maps folder", "--maps-dir"), name, ".map", true);
  RefuseExisting(path, overwrite, "SaveMap");
  std::error_code error;
  // Beside the target, so the rename stays on one file system; the pid keeps
  // two daemons sharing a folder apart, O_EXCL a stale leftover.
  std::string hidden = path.filename().string();  // built step by step: GCC 12 warns (-Wrestrict) on "." + ...
  hidden.insert(0, 1, '.');
  hidden += ".tmp";
  hidden += std::to_string(::getpid());
  const fs::path temporary = path.parent_path() / hidden;
  fs::remove(temporary, error);
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) Fail(proto::ERROR_CODE_IO, "cannot write " + Quoted(temporary.string()) + ": " + SystemReason(errno));
  const bool written = WriteAll(fd, text) && ::fsync(fd) == 0;
  const int write_error = errno;
  ::close(fd);
  if (!written || ::rename(temporary.c_str(), path.c_str()) != 0) {
    const int reason = written ? errno : write_error;
    fs::remove(temporary, error);
    Fail(proto::ERROR_CODE_IO,
         "cannot write " + Quoted(path.string()) + ": " + SystemReason(reason) + "; the file on disk is unchanged");
  }
}

std::string NewLogPath(const std::string& logs_dir, const std::string& name, bool overwrite) {
  if (logs_dir.empty()) {
    Fail(proto::ERROR_CODE_INVALID_STATE,
         "StartLog: sim4cvd was started without --logs-dir, so clients cannot write run logs; start it with "
         "--logs-dir DIR (or record the whole run with --log FILE)");
  }
  const fs::path path = Confined(Root(logs_dir, "logs folder", "--logs-dir"), name, ".s4log", true);
  RefuseExisting(path, overwrite, "StartLog");
  return path.string();
}

}  // namespace sim4cv::daemon
