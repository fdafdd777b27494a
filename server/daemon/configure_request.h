// A Configure request carried out by a file of its own
// (server/daemon/configure/NAME.cpp), listed once in configure_requests.cpp.
// Simulation::Apply hands it every request whose oneof case the table names;
// its fields reach it checked by CheckConfigure only if that switch names the
// case (a request CheckConfigure does not name passes the network thread as
// it is, and its file checks it here, on the sim thread, throwing
// ConfigureError: the same Error, one frame later). docs/architecture.md,
// "Extending sim4cv".
#pragma once

#include "server/daemon/simulation.h"
#include "sim4cv.pb.h"

namespace sim4cv::daemon {

struct ConfigureRequest {
  proto::Configure::RequestCase request_case;
  // Carries `request` out on the sim thread and fills `answer` (its
  // WorldInfo is filled afterwards), saying in `change` what it changed
  // beyond State; throws ConfigureError, changing nothing, if it cannot.
  void (*apply)(Simulation& simulation, const proto::Configure& request, proto::Configured& answer,
                Simulation::Change& change);
};

// The table's entry for `request_case`, or nullptr.
const ConfigureRequest* FindConfigureRequest(proto::Configure::RequestCase request_case);

}  // namespace sim4cv::daemon
