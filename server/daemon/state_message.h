// Copies the simulation State into its protocol message.
#pragma once

#include "server/sim/state.h"
#include "sim4cv.pb.h"

namespace sim4cv::daemon {

// Fills `out` (reusing its allocations) with every entity's pose and velocity.
void FillStateMessage(const sim::State& state, proto::State& out);

}  // namespace sim4cv::daemon
