// The driving case study's controller (docs/driving.md, "Controller"), the
// C++ twin of clients/python/sim4cv/driving_control.py: Controls (steering,
// throttle, brake) from the 4 predicted waypoints v1 h1 ... v4 h4 (metres;
// v forward, h POSITIVE TO THE RIGHT).
//
//   steering = clip(gain * atan2(h1, v1) / radians(max_steering_deg), -1, 1)
//              (v1 <= 0: -1, 0 or +1 by the sign of h1; steer_waypoint k aims
//              at waypoint k instead: vk, hk)
//   throttle = clip(t_max - k * |h4|, t_min, t_max)   (0 when speed >= max_speed)
//   brake    = 0
//   slowdown S > 0 (off by default): the cap falls to
//   max(min(4, max_speed), max_speed - S * |h4|) and the car brakes
//   clip(0.5 * (speed - cap), 0, 1) above it (driving_control.turn_speed_cap)
//   bend C > 0 (off by default): the aim point (v, h) moves towards the bend's
//   outside, h -= C * kappa * (v^2 + h^2) / 2 while |h4| <= bend_limit, kappa
//   the signed curvature through waypoints 1-3 (driving_control.bend_shift)
//
// Same defaults, same clamping and the same results as the Python module,
// NaN inputs included (the clamps are Python's min/max, see controller.cpp).
#pragma once

#include <array>
#include <limits>
#include <optional>

namespace sim4cv::driving {

// v1 h1 v2 h2 v3 h3 v4 h4, metres: the network's output (labels.csv order).
using Waypoints = std::array<float, 8>;

struct ControllerParams {
  double max_steering_deg = 35.0;  // CarParams.max_steering_deg: the wheel angle at steering +-1
  double gain = 1.0;               // multiplies the angle (1 = the paper)
  double t_max = 1.0;              // throttle on a straight (h4 = 0)
  double t_min = 0.3;              // throttle floor
  double k = 0.25;                 // throttle lost per metre of |h4|
  double slowdown = 0;             // m/s of speed cap lost per metre of |h4| (0: off)
  double steer_waypoint = 1;       // the waypoint the steering aims at, 1 (the paper) ... 4; 1.5: halfway between 1 and 2
  double bend = 0;                 // 0 ... 1: fraction of the chord's offset corrected in a bend (0: off)
  double bend_limit = std::numeric_limits<double>::infinity();  // m: no bend correction while |h4| exceeds it
};

struct DriveControls {
  double steering = 0;  // -1 (full left) ... +1 (full right)
  double throttle = 0;  // 0 ... 1
  double brake = 0;     // 0 ... 1: only when slowing for a turn
};

class Controller {
 public:
  // Throws std::invalid_argument for max_steering_deg <= 0 or unless
  // 0 <= t_min <= t_max <= 1, steer_waypoint outside 1 ... 4, bend outside
  // 0 ... 1 or bend_limit <= 0 (driving_control.py raises ValueError for them).
  explicit Controller(ControllerParams params = {});

  // Controls.steering in [-1, 1] (positive right) towards the waypoint (v1
  // forward, h1 right): gain * atan2(h1, v1) / max wheel angle, clamped.
  // v1 <= 0: -1, 0 or +1 by the sign of h1.
  double Steering(double v1, double h1) const;
  // Controls.throttle: clip(t_max - k * |h4|, t_min, t_max); 0 when both
  // speed and max_speed (m/s) are given and speed >= max_speed.
  double Throttle(double h4, std::optional<double> speed = std::nullopt,
                  std::optional<double> max_speed = std::nullopt) const;
  // Metres to the right the bend correction moves the aim point (v, h):
  // -bend * kappa * (v^2 + h^2) / 2, or 0 when |h4| > bend_limit.
  double BendShift(const Waypoints& waypoints, double v, double h) const;
  // (steering, throttle, brake) from the 8 numbers, for Client::SendControls.
  DriveControls FromWaypoints(const Waypoints& waypoints, std::optional<double> speed = std::nullopt,
                              std::optional<double> max_speed = std::nullopt) const;

  const ControllerParams& params() const { return params_; }

 private:
  ControllerParams params_;
};

}  // namespace sim4cv::driving
