// Wires the pieces together: scene -> sim thread -> transports, and runs
// until SIGINT or SIGTERM.
#pragma once

#include "server/daemon/config.h"

namespace sim4cv::daemon {

// Blocks SIGINT/SIGTERM in the calling thread (and so in every thread it
// starts), serves until one arrives, shuts down cleanly. Returns the exit code.
int RunDaemon(const Config& config);

}  // namespace sim4cv::daemon
