// The daemon's access token for Hello.token (docs/security.md): SIM4CV_TOKEN
// if set, else, for a local address, the file the daemon wrote for this
// endpoint ($XDG_RUNTIME_DIR/sim4cv/KIND-PORT.token, or ~/.cache/sim4cv/),
// readable only by the daemon's user; else none, and the daemon's refusal
// says where the token is.
#include <cstdlib>
#include <fstream>

#include "requests.h"

namespace sim4cv::detail {
namespace {

bool IsLocal(const std::string& host) {
  return host.empty() || host == "localhost" || host.rfind("127.", 0) == 0 || host == "::1" || host == "[::1]";
}

std::string TokenFolder() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  if (runtime != nullptr && *runtime == '/') return std::string(runtime) + "/sim4cv";
  const char* home = std::getenv("HOME");
  return std::string(home != nullptr && *home == '/' ? home : "/tmp") + "/.cache/sim4cv";
}

}  // namespace

std::string AccessToken(const std::string& kind, const std::string& host, uint16_t port) {
  const char* given = std::getenv("SIM4CV_TOKEN");
  if (given != nullptr && *given != '\0') return given;
  if (!IsLocal(host)) return {};
  std::ifstream file(TokenFolder() + "/" + kind + "-" + std::to_string(port) + ".token");
  std::string token;
  std::getline(file, token);
  return token.size() <= 256 ? token : std::string();
}

}  // namespace sim4cv::detail
