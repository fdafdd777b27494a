// Named event counters every transport can bump (dropped datagrams, dropped
// replies, ...), reported to clients in Stats and to the log at shutdown.
#pragma once

#include <cstdint>
#include <map>
#include <mutex>
#include <string>

namespace sim4cv::session {

class Counters {
 public:
  void Add(const std::string& name, uint64_t amount = 1) {
    std::lock_guard lock(mutex_);
    values_[name] += amount;
  }
  uint64_t Get(const std::string& name) const {
    std::lock_guard lock(mutex_);
    const auto it = values_.find(name);
    return it == values_.end() ? 0 : it->second;
  }
  std::map<std::string, uint64_t> Snapshot() const {
    std::lock_guard lock(mutex_);
    return values_;
  }

 private:
  mutable std::mutex mutex_;
  std::map<std::string, uint64_t> values_;
};

}  // namespace sim4cv::session
