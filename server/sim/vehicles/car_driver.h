// Drives a Car along a polyline at a set speed: pure pursuit on the rear axle
// for steering, a PI speed loop with drag feed-forward for throttle/brake.
// Parameters and structure: docs/vehicles.md#car-driver.
#pragma once

#include "server/sim/vehicles/car.h"
#include "server/sim/vehicles/pid.h"
#include "server/sim/vehicles/polyline.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

struct CarDriverParams {
  // Pure pursuit aims at the path point lookahead = clamp(lookahead_min +
  // lookahead_time * speed, lookahead_min, lookahead_max) metres of arc
  // length past the rear axle's projection.
  double lookahead_min = 3.0;   // m
  double lookahead_time = 0.6;  // s
  double lookahead_max = 12.0;  // m
  // Speed loop on the error in m/s; its output u is a longitudinal force in
  // units of max_engine_force (u > 0 throttle, u < 0 brake).
  PidGains speed{1.5, 0.3, 0.0, 0.5};
  // On an open path the set speed is capped so that the car can stop at the
  // end with this deceleration; within `stop_distance` of the end it brakes.
  double stop_deceleration = 2.0;  // m/s^2
  double stop_distance = 0.5;      // m
  // Progress along the path is tracked by searching only this far (m of
  // path) either side of the last projection, unless the car is more than
  // `relocate_distance` off that stretch: then the whole path is searched.
  double search_window = 20.0;     // m
  double relocate_distance = 5.0;  // m
};

class CarDriver {
 public:
  CarDriver(const CarParams& car, Polyline path, double set_speed, const CarDriverParams& params = {});

  // The controls for the next physics step, from the car's current state.
  CarControls Update(const VehicleState& car, double dt);

  void set_speed(double speed) { set_speed_ = speed; }
  double set_speed() const { return set_speed_; }
  const Polyline& path() const { return path_; }

 private:
  Polyline::Projection Track(const Eigen::Vector2d& rear_axle);
  double Steering(const Eigen::Vector2d& rear_axle, double arc_length, double yaw, double speed) const;
  double TargetSpeed(double arc_length) const;

  CarParams car_;
  Polyline path_;
  double set_speed_;
  CarDriverParams params_;
  Pid speed_pid_;
  bool saturated_high_ = false;  // last output beyond full throttle
  bool saturated_low_ = false;   // last output beyond full brake
  double progress_ = -1.0;       // arc length of the rear axle's last projection; < 0: none yet
};

}  // namespace sim4cv::vehicles
