// What a traffic plan is built from (docs/maps.md, "Traffic"), and the fixed
// sizes it lays traffic out with.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace sim4cv::traffic {

// From the daemon's flags or the protocol. TrafficPlan checks it and throws
// std::invalid_argument naming the flag (the names below) and its value.
struct TrafficConfig {
  int moving_cars = 0;         // --traffic-cars: kinematic cars driving the lanes
  int parked_cars = 0;         // --traffic-parked: static cars at the kerb of straight road tiles
  int pedestrians = 0;         // --traffic-pedestrians: walkers on crosswalk paths
  bool traffic_lights = true;  // --traffic-lights: one signal per junction approach
  uint64_t seed = 1;           // --traffic-seed: every random choice of the plan and of the cars
  double green_s = 8.0;        // --traffic-green: seconds each axis of a junction has green (> 0)
  double yellow_s = 2.0;       // --traffic-yellow: seconds of yellow after green (>= 0)
  double all_red_s = 1.0;      // --traffic-all-red: seconds both axes are red between (>= 0)
};

// A pose on the ground: z = 0, turned `heading` radians counter-clockwise
// from east about z.
struct Pose2 {
  Eigen::Vector2d position{0, 0};
  double heading = 0.0;
};

// The traffic car's body: the same box as the simulated car
// (vehicles::CarParams::chassis_half_extents), so one mesh serves both.
inline constexpr double kCarLength = 4.5;
inline constexpr double kCarWidth = 1.8;

// Street furniture around a junction, measured back along an arm from the
// junction tile's edge ("back") and across it from the road's centre line
// ("lateral", positive to the right of traffic coming in). The road edge is
// at lateral 2 * kLaneWidth / 2 = 4 m.
inline constexpr double kStopLineBack = 5.0;        // a car stopping for a light halts its front here
inline constexpr double kCrosswalkBack = 2.5;       // the crosswalk's centre line (it spans back 1..4 m)
inline constexpr double kCrosswalkHalfWidth = 1.5;  // along the road
inline constexpr double kCrosswalkReach = 5.5;      // lateral of each end: 1.5 m onto the pavement
inline constexpr int kWalkLines = 4;                // walking lines per crosswalk, one walker each,
inline constexpr double kWalkLineSpacing = 0.7;     // this far apart along the road, centred on the crosswalk
inline constexpr double kLightLateral = 5.0;        // the pole stands 1 m off the road edge
inline constexpr double kLightBack = 5.0;           // level with the stop line, unless an object is in the way
inline constexpr double kParkedLateral = 5.2;       // a parked car's centre: its body spans lateral 4.3..6.1 m

// Moving cars start at least this far apart along their lanes.
inline constexpr double kStartSpacing = 12.0;
// Each moving car cruises at a speed drawn from this range, m/s.
inline constexpr double kMinCruiseSpeed = 5.0;
inline constexpr double kMaxCruiseSpeed = 8.0;
// Each walker walks at a speed drawn from this range, m/s, and pauses at
// each end of its path for a time drawn from the next, s.
inline constexpr double kMinWalkSpeed = 1.1;
inline constexpr double kMaxWalkSpeed = 1.5;
inline constexpr double kMinPause = 1.0;
inline constexpr double kMaxPause = 3.0;
// A walker's body, for the cars' look-ahead: a disc of this radius.
inline constexpr double kWalkerRadius = 0.3;

}  // namespace sim4cv::traffic
