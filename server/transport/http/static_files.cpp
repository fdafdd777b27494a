#include "server/transport/http/static_files.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

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

}  // namespace

StaticFiles::StaticFiles(const std::string& folder) {
  namespace fs = std::filesystem;
  std::error_code error;
  std::size_t total = 0;
  const fs::path root(folder);
  for (fs::recursive_directory_iterator it(root, error), end; !error && it != end; it.increment(error)) {
    std::error_code status_error;
    if (it->is_symlink(status_error) || !it->is_regular_file(status_error)) continue;
    const char* type = ContentType(it->path().extension().string());
    if (type == nullptr) continue;
    std::ifstream in(it->path(), std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    if (!in) throw std::runtime_error("--studio-dir: cannot read " + it->path().string());
    total += bytes.str().size();
    if (total > kMaxBytes) {
      throw std::runtime_error("--studio-dir " + folder + " holds more than " + std::to_string(kMaxBytes >> 20) +
                               " MiB of page files; point it at the studio/ folder");
    }
    std::string url(1, '/');  // (not "/" + ...: GCC 12 warns falsely about that, -Wrestrict)
    url += it->path().lexically_relative(root).generic_string();
    files_[url] = File{type, bytes.str()};
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
