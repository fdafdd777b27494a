#include "server/daemon/access_token_files.h"

#include <fcntl.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "server/common/beneath.h"
#include "server/common/regular_file.h"

namespace sim4cv::daemon {
namespace {

constexpr std::size_t kMinTokenBytes = 16;
constexpr std::size_t kMaxTokenBytes = 256;

[[noreturn]] void FailSystem(const std::string& what, const std::string& path) {
  throw std::runtime_error(what + " '" + path + "': " + std::strerror(errno));
}

// `path` as a folder this user owns that no one else may enter: made 0700
// if missing, narrowed to 0700 if this user's, refused if another's.
Fd PrivateFolder(const std::string& path) {
  if (::mkdir(path.c_str(), 0700) != 0 && errno != EEXIST) FailSystem("cannot create the token folder", path);
  Fd folder(::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC));
  if (!folder.valid()) FailSystem("cannot open the token folder", path);
  struct stat info {};
  if (::fstat(folder.get(), &info) != 0) FailSystem("cannot inspect the token folder", path);
  if (info.st_uid != ::geteuid()) {
    throw std::runtime_error("the token folder '" + path + "' belongs to user " + std::to_string(info.st_uid) +
                             ", not this one (" + std::to_string(::geteuid()) +
                             "); remove it, or set XDG_RUNTIME_DIR to a folder of your own");
  }
  if ((info.st_mode & 0077) != 0 && ::fchmod(folder.get(), 0700) != 0) {
    FailSystem("cannot make the token folder private", path);
  }
  return folder;
}

std::string Hex(const unsigned char* bytes, std::size_t count) {
  static const char kDigits[] = "0123456789abcdef";
  std::string text;
  for (std::size_t i = 0; i < count; ++i) {
    text += kDigits[bytes[i] >> 4];
    text += kDigits[bytes[i] & 15];
  }
  return text;
}

}  // namespace

std::string TokenFolder() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  if (runtime != nullptr && *runtime == '/') return std::string(runtime) + "/sim4cv";
  const char* home = std::getenv("HOME");
  return std::string(home != nullptr && *home == '/' ? home : "/tmp") + "/.cache/sim4cv";
}

std::string LoadOrMakeToken(const Config& config) {
  if (config.no_auth) return {};
  if (!config.token_file.empty()) {
    std::string text = ReadRegularFile(config.token_file, "--token-file", 4096, "4096 bytes");
    text = text.substr(0, text.find('\n'));
    bool printable = true;
    for (char c : text) printable = printable && c > ' ' && c < 127;
    if (!printable || text.size() < kMinTokenBytes || text.size() > kMaxTokenBytes) {
      throw std::invalid_argument("--token-file '" + config.token_file + "': its first line must be a token of " +
                                  std::to_string(kMinTokenBytes) + " to " + std::to_string(kMaxTokenBytes) +
                                  " printable characters without spaces, e.g. from `openssl rand -hex 32`");
    }
    return text;
  }
  unsigned char bytes[32];
  for (std::size_t done = 0; done < sizeof bytes;) {
    const ssize_t n = ::getrandom(bytes + done, sizeof bytes - done, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw std::runtime_error(std::string("cannot draw an access token: ") + std::strerror(errno));
    done += static_cast<std::size_t>(n);
  }
  return Hex(bytes, sizeof bytes);
}

AccessTokenFiles::AccessTokenFiles(const std::string& token, const std::vector<std::string>& names) : token_(token) {
  const std::string folder_path = TokenFolder();
  // ~/.cache itself may be missing on a fresh account.
  const std::size_t parent_end = folder_path.rfind('/');
  if (parent_end != std::string::npos && parent_end > 0) ::mkdir(folder_path.substr(0, parent_end).c_str(), 0700);
  const Fd folder = PrivateFolder(folder_path);
  const std::string temporary = ".token.tmp" + std::to_string(::getpid());
  for (const std::string& name : names) {
    const std::string leaf = name + ".token";
    const std::string path = folder_path + "/" + leaf;
    ::unlinkat(folder.get(), temporary.c_str(), 0);
    const Fd fd(::openat(folder.get(), temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600));
    if (!fd.valid()) FailSystem("cannot write the token file", path);
    const std::string line = token + "\n";
    if (::write(fd.get(), line.data(), line.size()) != static_cast<ssize_t>(line.size()) ||
        ::renameat(folder.get(), temporary.c_str(), folder.get(), leaf.c_str()) != 0) {
      ::unlinkat(folder.get(), temporary.c_str(), 0);
      FailSystem("cannot write the token file", path);
    }
    paths_.push_back(path);
  }
}

AccessTokenFiles::~AccessTokenFiles() {
  for (const std::string& path : paths_) {
    try {
      // A later daemon on the same port may have written its own since.
      if (ReadRegularFile(path, "token file", 4096, "4096 bytes") == token_ + "\n") ::unlink(path.c_str());
    } catch (const std::exception&) {
    }
  }
}

}  // namespace sim4cv::daemon
