// sim4cvd: flags -> Config -> daemon.
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "server/daemon/config.h"
#include "server/daemon/daemon.h"

int main(int argc, char** argv) {
  try {
    std::string help;
    const auto config = sim4cv::daemon::ParseFlags(std::vector<std::string>(argv + 1, argv + argc), help);
    if (!config) {
      std::fputs(help.c_str(), stdout);
      return 0;
    }
    return sim4cv::daemon::RunDaemon(*config);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "sim4cvd: %s\n", error.what());
    return 2;
  }
}
