// Each TCP connection takes a file descriptor: checked at start against the
// process's limit (RLIMIT_NOFILE), so --max-clients cannot promise more
// connections than the daemon can accept (docs/reliability.md, finding 12).
#pragma once

#include <cstdint>
#include <string>

namespace sim4cv::transport {

// Makes sure `max_clients` connections plus limits::kReservedDescriptors fit
// under the soft descriptor limit, raising it towards the hard limit if
// needed. Throws std::runtime_error naming both numbers if they cannot fit.
void EnsureDescriptorsFor(uint32_t max_clients);
// The same for `connections` promised by several flags (the studio's HTTP
// port adds its --http-max-clients to TCP's): `flags` names them, e.g.
// "--max-clients 64 plus --http-max-clients 32".
void EnsureDescriptorsFor(uint32_t connections, const std::string& flags);

// "N descriptors open, limit M": for the log when accept() fails.
std::string DescriptorUsage();

}  // namespace sim4cv::transport
