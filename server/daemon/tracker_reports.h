// The trackers' latest reports in State (one per client, ordered by client
// id, so State and the run log list them the same way every run): what a
// TrackerOutput updates and a disconnect erases (issue 14, finding 6).
#pragma once

#include "server/session/command.h"
#include "server/sim/state.h"

namespace sim4cv::daemon {

// Replaces `client`'s report with `output`, or adds it in client-id order.
void RecordTrackerReport(sim::State& state, session::ClientId client, const session::TrackerOutputCommand& output);
// Erases `client`'s report, if any.
void ForgetTrackerReport(sim::State& state, session::ClientId client);

}  // namespace sim4cv::daemon
