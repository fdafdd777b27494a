// Tracking in the loop (docs/tracking.md, "The servo"): a UAV whose order is
// kTrack steers by the newest box the trackers of its camera report, as a
// real drone follows what its tracker sees. The box centre is cast as a ray
// through the camera (its field of view and the gimbal's pitch are known)
// onto the ground: that is where the target is. The UAV then holds station
// `distance` behind it and faces it, with the target's velocity (from
// successive estimates, smoothed) fed forward, exactly as the follow order
// does with the true pose. Nothing but the box reaches the servo, so a
// tracker's errors and lag become the UAV's. The gains live here, in one
// place, tuned with the ground-truth tracker (tests/integration/tracking_servo_test.cpp).
#pragma once

#include <cstdint>
#include <optional>

#include "server/sim/state.h"
#include "server/sim/vehicles/quadcopter_controller.h"

namespace sim4cv::sim {

struct TrackServoGains {
  double velocity_smoothing = 0.3;  // weight of a new velocity estimate (exponential smoothing)
  double target_height = 0.75;      // m: the box centre's height above the ground (a car's middle)
  double report_timeout = 1.0;      // s: an older newest box holds the UAV still
};
inline constexpr TrackServoGains kTrackServo{};

// The command for a kTrack UAV `uav_id` this physics step; updates the
// order's memory (the target estimate) when a newer box has come.
vehicles::QuadcopterCommand TrackCommand(UavOrder& order, uint32_t uav_id, const BodyState& uav, const State& state);

// The newest report whose box is in a camera on `entity_id`, or nullptr.
const TrackerReport* NewestReportFor(const State& state, uint32_t entity_id);

// Where the box's centre lies on the ground, relative to the UAV, in its
// heading frame (x forward, y left), metres; nullopt if the ray does not
// come down to the ground (the box is above the horizon).
std::optional<Eigen::Vector2d> GroundOffset(const UavOrder::Track& camera, const TrackerReport& box, double height);

}  // namespace sim4cv::sim
