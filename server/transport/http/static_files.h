// The studio's files, read once when the daemon starts: a request can only
// ever get one of them by its exact path, so no URL (with "..", "%2e%2e",
// links or anything else) reaches another file, and serving touches no disk.
// Editing the page means restarting the daemon.
#pragma once

#include <map>
#include <string>
#include <string_view>

namespace sim4cv::transport {

class StaticFiles {
 public:
  struct File {
    std::string content_type;
    std::string bytes;
  };

  // Every regular file under `folder` (recursively, links not followed) with
  // an extension the page uses (.html .js .css .svg .png .json .ico .txt).
  // Throws std::runtime_error naming the folder if it has no index.html, or
  // if the files exceed kMaxBytes in all.
  explicit StaticFiles(const std::string& folder);

  // The file a request's target names ("/" is "/index.html"; a query string
  // is ignored), or null.
  const File* Find(std::string_view target) const;

  std::size_t count() const { return files_.size(); }

  static constexpr std::size_t kMaxBytes = 32u << 20;

 private:
  std::map<std::string, File, std::less<>> files_;  // by URL path, e.g. "/js/live.js"
};

}  // namespace sim4cv::transport
