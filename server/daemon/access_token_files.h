// The daemon's access token (docs/security.md) and the files that hand it to
// its own user's clients: one per listening endpoint, named after it
// (tcp-PORT.token, udp-PORT.token, http-PORT.token, shm-NAME.token) in
// $XDG_RUNTIME_DIR/sim4cv/ or, without it, ~/.cache/sim4cv/: a folder only
// this user may enter (0700), files only this user may read (0600). A client
// of another user cannot read them, so it cannot say Hello.
#pragma once

#include <string>
#include <vector>

#include "server/daemon/config.h"

namespace sim4cv::daemon {

// The folder token files live in, for this process's environment.
std::string TokenFolder();

// The token: --token-file's first line, or 32 random bytes as 64 hex
// digits. Throws std::invalid_argument naming the file if it cannot be read
// or holds no token of 16 to 256 printable characters.
std::string LoadOrMakeToken(const Config& config);

class AccessTokenFiles {
 public:
  // Writes `token` to TokenFolder()/NAME.token for each of `names` (each
  // replaced atomically). Throws std::runtime_error naming the folder or
  // file when that cannot be done safely (a folder another user owns, ...).
  AccessTokenFiles(const std::string& token, const std::vector<std::string>& names);
  // Removes the files, if they still hold this daemon's token.
  ~AccessTokenFiles();
  AccessTokenFiles(const AccessTokenFiles&) = delete;
  AccessTokenFiles& operator=(const AccessTokenFiles&) = delete;

  const std::vector<std::string>& paths() const { return paths_; }

 private:
  std::string token_;
  std::vector<std::string> paths_;
};

}  // namespace sim4cv::daemon
