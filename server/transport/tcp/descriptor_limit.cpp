#include "server/transport/tcp/descriptor_limit.h"

#include <dirent.h>
#include <sys/resource.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "server/common/diagnostics.h"
#include "server/common/limits.h"

namespace sim4cv::transport {
namespace {

std::string Text(rlim_t value) { return value == RLIM_INFINITY ? "unlimited" : std::to_string(value); }

}  // namespace

void EnsureDescriptorsFor(uint32_t max_clients) {
  EnsureDescriptorsFor(max_clients, "--max-clients " + std::to_string(max_clients));
}

void EnsureDescriptorsFor(uint32_t max_clients, const std::string& flags) {
  rlimit limit{};
  if (getrlimit(RLIMIT_NOFILE, &limit) != 0) {
    throw std::runtime_error(std::string("cannot read the file descriptor limit (RLIMIT_NOFILE): ") +
                             std::strerror(errno));
  }
  const rlim_t need = static_cast<rlim_t>(max_clients) + limits::kReservedDescriptors;
  if (limit.rlim_cur == RLIM_INFINITY || limit.rlim_cur >= need) return;
  if (limit.rlim_max == RLIM_INFINITY || limit.rlim_max >= need) {
    const rlim_t before = limit.rlim_cur;
    limit.rlim_cur = need;
    if (setrlimit(RLIMIT_NOFILE, &limit) == 0) {
      LOG_INFO("raised the file descriptor limit from " << before << " to " << need << " for " << flags);
      return;
    }
    limit.rlim_cur = before;
  }
  const rlim_t hard = limit.rlim_max;
  std::string advice = "raise the limit (ulimit -n)";
  if (hard != RLIM_INFINITY && hard > limits::kReservedDescriptors) {
    const std::string which = flags.find(" plus ") == std::string::npos ? "--max-clients" : "them";
    advice = "lower " + which + " to at most " + std::to_string(hard - limits::kReservedDescriptors) +
             (which == "them" ? " in all" : "") + ", or " + advice;
  }
  throw std::runtime_error(flags + " needs " + std::to_string(need) + " file descriptors (one per connection plus " +
                           std::to_string(limits::kReservedDescriptors) +
                           " for the daemon's own), but the descriptor limit (RLIMIT_NOFILE) is " +
                           Text(limit.rlim_cur) + ", hard limit " + Text(hard) + "; " + advice);
}

std::string DescriptorUsage() {
  int open = 0;
  if (DIR* dir = opendir("/proc/self/fd")) {  // needs a descriptor itself: may fail when out of them
    while (const dirent* entry = readdir(dir)) open += entry->d_name[0] != '.';
    closedir(dir);
    --open;  // the directory's own
  }
  rlimit limit{};
  getrlimit(RLIMIT_NOFILE, &limit);
  return (open > 0 ? std::to_string(open) : std::string("?")) + " descriptors open, limit " + Text(limit.rlim_cur);
}

}  // namespace sim4cv::transport
