// What the HTTP transport's connections share, on its Asio thread only: the
// options, the page's files, the server context, and the registry of open
// connections (plain HTTP and WebSocket alike), which caps how many are
// served and closes them all at Stop.
#pragma once

#include <cstdint>
#include <map>
#include <memory>

#include "server/session/server_context.h"
#include "server/transport/http/http_transport.h"
#include "server/transport/http/static_files.h"

namespace sim4cv::transport {

// An open connection, as the registry sees it.
class HttpPeer {
 public:
  virtual ~HttpPeer() = default;
  // Closes the socket at once (a WebSocket also ends its client session).
  virtual void Close() = 0;
  // Whether it has completed nothing yet (no request, no Hello): at
  // capacity the oldest such connection makes room for a newcomer.
  virtual bool half_open() const = 0;
};

class HttpHub {
 public:
  HttpHub(const HttpOptions& options, const StaticFiles& files) : options(options), files(files) {}

  const HttpOptions& options;
  const StaticFiles& files;
  const session::ServerContext* context = nullptr;  // set at Start

  // A connection under `key`: served (counts against max_clients), or being
  // refused (counts against limits::kMaxHttpRejecting). A connection that
  // becomes a WebSocket session registers the session under its key.
  void Register(uint64_t key, std::shared_ptr<HttpPeer> peer, bool rejecting) {
    peers_[key] = Entry{std::move(peer), rejecting};
  }
  void Forget(uint64_t key) { peers_.erase(key); }
  std::size_t Count(bool rejecting) const {
    std::size_t count = 0;
    for (const auto& [key, entry] : peers_) count += entry.rejecting == rejecting;
    return count;
  }
  // Closes the oldest served connection that is half open (keys grow with
  // time), so a client that keeps reconnecting half-sent requests cannot
  // hold every slot. Whether there was one.
  bool ReclaimStalestHalfOpen() {
    for (auto& [key, entry] : peers_) {
      if (entry.rejecting || !entry.peer->half_open()) continue;
      const std::shared_ptr<HttpPeer> stalest = entry.peer;  // Close() forgets it
      stalest->Close();
      return true;
    }
    return false;
  }
  void CloseAll() {
    auto open = peers_;  // Close() forgets itself
    for (auto& [key, entry] : open) entry.peer->Close();
    peers_.clear();
  }

 private:
  struct Entry {
    std::shared_ptr<HttpPeer> peer;
    bool rejecting = false;
  };
  std::map<uint64_t, Entry> peers_;
};

}  // namespace sim4cv::transport
