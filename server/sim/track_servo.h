// Tracking in the loop (docs/tracking.md, "The servo"): a UAV whose order is
// kTrack steers by the newest box the trackers of its cameras report, as a
// real drone following what its tracker sees. Proportional-integral terms on
// the box centre's horizontal offset (yaw) and on the target's apparent
// distance (forward speed: the box's vertical offset and its height against
// the reference); altitude held. The gains live here, in one place, tuned
// with the ground-truth tracker (tests/integration/tracking_servo_test.cpp).
#pragma once

#include <cstdint>

#include "server/sim/state.h"
#include "server/sim/vehicles/quadcopter_controller.h"

namespace sim4cv::sim {

struct TrackServoGains {
  double yaw_p = 1.6;                // rad/s per unit offset (box centre at the image edge: 1)
  double yaw_i = 0.4;                // rad/s per unit offset and second
  double forward_p = 10.0;           // m/s per unit distance error
  double forward_i = 4.0;            // m/s per unit distance error and second
  double height_weight = 1.0;        // distance error per unit relative height error
  double offset_weight = 1.0;        // distance error per unit vertical offset (box low: near)
  double altitude_p = 1.0;           // m/s per metre of altitude error
  double max_speed = 20.0;           // m/s, horizontal
  double max_yaw_rate = 1.5;         // rad/s
  double report_timeout = 1.0;       // s: an older newest box holds the UAV still
  double max_integral = 5.0;         // anti-windup bound of each integral
};
inline constexpr TrackServoGains kTrackServo{};

// The command for a kTrack UAV `uav_id` this physics step of `dt` seconds;
// updates `order.track`'s memory (reference height, integrals).
vehicles::QuadcopterCommand TrackCommand(UavOrder& order, uint32_t uav_id, const BodyState& uav, const State& state,
                                         double dt);

// The newest report whose box is in a camera on `entity_id`, or nullptr.
const TrackerReport* NewestReportFor(const State& state, uint32_t entity_id);

}  // namespace sim4cv::sim
