// Addresses of sim4cvd's transports: tcp://HOST:PORT, udp://HOST:PORT,
// shm://NAME. The one place that maps a scheme to its Link: a new transport
// is one more line in OpenLink.
#include <stdexcept>

#include "link.h"

namespace sim4cv::detail {
namespace {

constexpr const char* kForms = "tcp://HOST:PORT, udp://HOST:PORT or shm://NAME";

[[noreturn]] void Refuse(const std::string& address, const std::string& why) {
  throw std::invalid_argument("sim4cv address '" + address + "' " + why + "; use " + kForms);
}

// HOST:PORT of `rest`, the port 1 .. 65535.
std::pair<std::string, uint16_t> HostPort(const std::string& address, const std::string& rest) {
  const auto colon = rest.rfind(':');
  if (colon == std::string::npos || colon == 0) Refuse(address, "has no HOST:PORT");
  const std::string port = rest.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos ||
      std::stoul(port) == 0 || std::stoul(port) > 65535) {
    Refuse(address, "has port '" + port + "', not a number from 1 to 65535");
  }
  return {rest.substr(0, colon), static_cast<uint16_t>(std::stoul(port))};
}

}  // namespace

std::unique_ptr<Link> OpenLink(const std::string& address, Deadline deadline, uint32_t max_message_bytes) {
  const auto scheme_end = address.find("://");
  if (scheme_end == std::string::npos) Refuse(address, "names no transport");
  const std::string scheme = address.substr(0, scheme_end);
  const std::string rest = address.substr(scheme_end + 3);
  if (scheme == "tcp") {
    const auto [host, port] = HostPort(address, rest);
    return OpenTcpLink(host, port, deadline, max_message_bytes);
  }
  if (scheme == "udp") {
    const auto [host, port] = HostPort(address, rest);
    return OpenUdpLink(host, port);
  }
  if (scheme == "shm") {
    if (rest.empty() || rest == "/") Refuse(address, "has no object name");
    return OpenShmLink(rest);
  }
  Refuse(address, "names the transport '" + scheme + "'");
}

}  // namespace sim4cv::detail
