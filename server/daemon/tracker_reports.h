// The trackers' latest reports in State (one per client, ordered by client
// id, so State and the run log list them the same way every run): what a
// TrackerOutput updates and a disconnect erases (docs/reliability.md, finding 6). A
// report is checked against the client's camera and the frames rendered
// first, since a kTrack UAV steers by it (server/sim/track_servo.h).
#pragma once

#include <string>
#include <string_view>

#include "server/session/command.h"
#include "server/sim/state.h"

namespace sim4cv::daemon {

// The camera a client's boxes are in (the one it subscribes to).
struct ReportCamera {
  std::string_view name;   // the camera list's, valid while it is
  uint32_t entity_id = 0;  // the entity it is mounted on; 0: fixed in the world
  uint32_t width = 0, height = 0;
};

// Replaces `client`'s report with `output`, or adds it in client-id order,
// if it is a box in `camera` (nullptr: the client subscribes to none) for a
// frame rendered already and after the client's last report. Otherwise
// changes nothing and returns why, for the client's Error.
std::string RecordTrackerReport(sim::State& state, session::ClientId client,
                                const session::TrackerOutputCommand& output, const ReportCamera* camera);
// Erases `client`'s report, if any.
void ForgetTrackerReport(sim::State& state, session::ClientId client);

}  // namespace sim4cv::daemon
