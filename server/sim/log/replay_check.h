// The values --replay takes from a run log, checked as strictly as a
// client's (docs/logs.md, "Replay"): a record passes its CRC whatever pose it
// holds, and a log from a run whose physics blew up holds non-finite or
// absurd ones, which would reach the renderer's camera maths on the first
// replayed frame (docs/reliability.md, finding 3).
#pragma once

#include "server/sim/log/replay_track.h"

namespace sim4cv::runlog {

// Throws std::invalid_argument naming the first bad value: its record (0-based,
// in log order), frame id, entity id and field, the value, and the limit it
// breaks (limits::kMaxWorldCoordinate, limits::kLogQuaternionNormTolerance).
// Checks each record's sim_time (finite, >= 0) and every entity's position,
// orientation (a unit quaternion) and linear and angular velocity.
void CheckReplayValues(const ReplayTrack& track);

}  // namespace sim4cv::runlog
