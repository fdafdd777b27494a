// The mutable half of traffic (after MuJoCo's mjData): everything a step
// changes, and the step itself. Same plan, same initial state, same steps
// (times, dt, obstacles) give bit-identical states.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "server/sim/map/road_graph.h"
#include "server/sim/traffic/traffic_plan.h"

namespace sim4cv::traffic {

// How many lane segments a moving car has decided ahead (its own one
// included): enough for its 40 m look-ahead even through the shortest
// segments (a 6.3 m right turn on 12 m tiles).
inline constexpr int kPlannedSegments = 8;

struct MovingCar {
  map::LanePoint lane;  // its centre, always on a lane's centre line
  // route[0] == lane.segment; then the segments it will drive next, turns
  // at junctions drawn from rng_state as it goes.
  std::array<map::SegmentId, kPlannedSegments> route{};
  map::SegmentId came_from = -1;  // the segment it drove before route[0], -1 at the start
  double speed = 0.0;             // along the lane, m/s, >= 0
  double cruise_speed = 0.0;      // what it drives at on a free straight road, m/s
  double acceleration = 0.0;      // over the last step, m/s^2 (negative: braking)
  // The junction segment it has decided to stop before (a light that is not
  // green, or a car it gives way to), -1 if none. The decision holds until it
  // may go, so a car creeping up to its line does not change its mind.
  map::SegmentId stopping_for = -1;
  // The junction segment it claims (is in, or is about to enter), -1 if
  // none, and since when (sim time, s): junctions are first come, first served.
  map::SegmentId claimed = -1;
  double claimed_since = 0.0;
  uint64_t rng_state = 0;                              // its own splitmix64 stream
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // z = 0: the caller adds the body's height
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  double heading = 0.0;   // radians, = lane.heading
  double yaw_rate = 0.0;  // rad/s, counter-clockwise
};

struct Walker {
  int path = 0;             // index into plan.walk_paths()
  double s = 0.0;           // metres from the path's start
  int direction = 1;        // +1 walking towards its end, -1 back towards its start
  double speed = 0.0;       // m/s while walking
  double pause_left = 0.0;  // s still to stand at the kerb; at 0 it walks, or waits for red and a gap
  uint64_t rng_state = 0;   // its own splitmix64 stream (pause lengths)
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // feet, z = 0
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();
  double heading = 0.0;  // where it faces: its walking direction
};

// What one step works out for a car before any car moves, so the order cars
// are stepped in does not matter. Rebuilt every step: scratch, not state.
struct CarStepWork {
  map::SegmentId junction_segment = -1;  // the junction segment it is in, or the next one on its route
  double to_junction = std::numeric_limits<double>::infinity();  // from its centre to that segment's start
  bool inside = false;                                           // in a junction now
  bool claims = false;         // inside, or going to enter (not held by a light) within the claim distance
  double claimed_since = 0.0;  // sim time it began to claim junction_segment
  double stop_at = std::numeric_limits<double>::infinity();  // metres it may go before a stop line or yield point
  map::SegmentId stopping_for = -1;  // what stop_at stops it before (becomes MovingCar::stopping_for)
  double acceleration = 0.0;
  double free_distance = std::numeric_limits<double>::infinity();  // the most it may move this step
};

// A vehicle traffic does not move but must keep clear of: a car the World
// simulates (the target car, spawned cars), as an oriented car-sized box.
struct Obstacle {
  Eigen::Vector2d position{0, 0};  // its centre
  double heading = 0.0;            // radians, counter-clockwise from east
  double speed = 0.0;              // forward, m/s
};

struct TrafficState {
  std::vector<MovingCar> cars;
  std::vector<Walker> walkers;
  std::vector<CarStepWork> work;  // scratch, one per car; kept here so a step allocates nothing
};

// A car at rest (or at `speed`) on `segment` at arc length `s`, with its
// route drawn from `rng_seed`.
MovingCar CarAt(const TrafficPlan& plan, map::SegmentId segment, double s, double cruise_speed, uint64_t rng_seed,
                double speed = 0.0);

// The cars and walkers where the plan starts them, at rest.
TrafficState InitialTraffic(const TrafficPlan& plan);

// Advances by `dt` seconds (> 0) from `sim_time` (the time at the step's
// start, which the lights are read at). `obstacles` are the other vehicles
// (the simulated, physics-driven ones): a moving car treats one lying ahead
// in its lane corridor as a standing car and stops behind it; a walker
// neither steps off the kerb while one is on or coming at its crosswalk nor
// walks into one. Allocates nothing once state.work matches state.cars.
void StepTraffic(const TrafficPlan& plan, TrafficState& state, double sim_time, double dt,
                 std::span<const Obstacle> obstacles);

namespace detail {
// The moving-car half of StepTraffic (traffic_cars.cpp); call StepTraffic.
void StepCars(const TrafficPlan& plan, TrafficState& state, double sim_time, double dt,
              std::span<const Obstacle> obstacles);
}  // namespace detail

}  // namespace sim4cv::traffic
