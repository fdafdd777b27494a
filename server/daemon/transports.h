// The ways clients reach the daemon, listed once: each made from the flags
// (or not, when they turn it off), in the order of the listening line and of
// Welcome.transports. docs/architecture.md, "Extending sim4cv".
#pragma once

#include <memory>
#include <vector>

#include "server/daemon/config.h"
#include "server/sim/scene.h"
#include "server/transport/transport.h"

namespace sim4cv::daemon {

struct TransportEntry {
  const char* name;  // "tcp", for messages
  // The transport the flags ask for, bound and listening (not yet serving);
  // nullptr when they turn it off. Throws naming what cannot be done.
  std::unique_ptr<transport::Transport> (*make)(const Config& config, const sim::Scene& scene);
};

// A transport made outside transports.cpp's table (one in a test, or linked
// into a daemon of one's own): registered before RunDaemon, it is made after
// the table's, in the order of registration.
void RegisterTransport(TransportEntry entry);

// The table's transports, then the registered ones.
std::vector<std::unique_ptr<transport::Transport>> MakeTransports(const Config& config, const sim::Scene& scene);

}  // namespace sim4cv::daemon
