// Copies the simulation State into its protocol message.
#pragma once

#include "server/sim/scene.h"
#include "server/sim/state.h"
#include "sim4cv.pb.h"

namespace sim4cv::daemon {

// Fills `out` (reusing its allocations) with every entity's pose and velocity.
void FillStateMessage(const sim::Scene& scene, const sim::State& state, proto::State& out);

// The entities a Welcome lists.
void FillEntityInfos(const sim::Scene& scene, proto::Welcome& welcome);

}  // namespace sim4cv::daemon
