#include "server/transport/http/static_files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <system_error>

#include "server/common/beneath.h"

namespace sim4cv::transport {
namespace {

const char* ContentType(const std::string& extension) {
  static const std::map<std::string, const char*, std::less<>> kTypes = {
      {".html", "text/html; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"},
      {".css", "text/css; charset=utf-8"},
      {".svg", "image/svg+xml"},
      {".png", "image/png"},
      {".json", "application/json"},
      {".ico", "image/x-icon"},
      {".txt", "text/plain; charset=utf-8"},
  };
  const auto found = kTypes.find(extension);
  return found == kTypes.end() ? nullptr : found->second;
}

// The bytes of `relative` beneath the folder `folder`, opened with no link
// followed (server/common/beneath.h) and only if it is a regular file.
std::optional<std::string> ReadBeneath(int folder, const std::string& relative) {
  const Fd fd(OpenBeneath(folder, relative, O_RDONLY | O_NONBLOCK));
  struct stat info {};
  if (!fd.valid() || ::fstat(fd.get(), &info) != 0 || !S_ISREG(info.st_mode)) return std::nullopt;
  std::string bytes;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(fd.get(), buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::nullopt;
    if (n == 0) return bytes;
    bytes.append(buffer, static_cast<std::size_t>(n));
    if (bytes.size() > StaticFiles::kMaxBytes) return bytes;  // the caller's total refuses it
  }
}

}  // namespace

StaticFiles::StaticFiles(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code error;
  std::size_t total = 0;
  const fs::path root(folder);
  const Fd root_fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  for (fs::recursive_directory_iterator it(root, error), end; root_fd.valid() && !error && it != end;
       it.increment(error)) {
    // Hidden files and folders (.git, .env, an editor's swap file) are not the page's.
    if (it->path().filename().string().front() == '.') {
      it.disable_recursion_pending();
      continue;
    }
    std::error_code status_error;
    if (it->is_symlink(status_error) || !it->is_regular_file(status_error)) continue;
    const char* type = ContentType(it->path().extension().string());
    if (type == nullptr) continue;
    const std::string relative = it->path().lexically_relative(root).generic_string();
    std::optional<std::string> bytes = ReadBeneath(root_fd.get(), relative);
    if (!bytes) throw std::runtime_error("--studio-dir: cannot read " + it->path().string() + " as a regular file");
    total += bytes->size();
    if (total > kMaxBytes) {
      throw std::runtime_error("--studio-dir " + folder + " holds more than " + std::to_string(kMaxBytes >> 20) +
                               " MiB of page files; point it at the studio/ folder");
    }
    std::string url(1, '/');  // (not "/" + ...: GCC 12 warns falsely about that, -Wrestrict)
    url += relative;
    files_[url] = File{type, std::move(*bytes)};
  }
  if (files_.find("/index.html") == files_.end()) {
    throw std::runtime_error("--studio-dir " + folder + " has no index.html" +
                             (error ? " (" + error.message() + ")" : std::string()) +
                             "; point it at the studio/ folder of the source tree or of the installation");
  }
}

const StaticFiles::File* StaticFiles::Find(std::string_view target) const {
  target = target.substr(0, target.find('?'));
  if (target == "/") target = "/index.html";
  const auto found = files_.find(target);
  return found == files_.end() ? nullptr : &found->second;
}

}  // namespace sim4cv::transport
