// A scalar PID shared by the car's speed loop and the quadcopter's loops.
#pragma once

#include <algorithm>
#include <cmath>

namespace sim4cv::vehicles {

struct PidGains {
  double kp = 0.0;
  double ki = 0.0;
  double kd = 0.0;
  double integral_limit = 1e9;  // |ki * integral| never exceeds this (output units)
  double integral_zone = 1e9;   // integrates only while |error| is below this (error units)
};

class Pid {
 public:
  explicit Pid(const PidGains& gains) : gains_(gains) {}

  // `error_rate` is the error's time derivative, supplied by the caller from a
  // measured velocity rather than by differencing a sampled error (which
  // would amplify quantisation and setpoint jumps). Pass integrate = false
  // while the caller's output is saturated in the error's direction
  // (conditional integration: the integrator cannot wind up).
  double Update(double error, double error_rate, double dt, bool integrate = true) {
    // Integral separation: a large error is a transient for P and D to
    // handle; integrating it too would only leave a bias to unwind later.
    if (integrate && gains_.ki != 0.0 && std::abs(error) < gains_.integral_zone) {
      const double limit = gains_.integral_limit / gains_.ki;
      integral_ = std::clamp(integral_ + error * dt, -limit, limit);
    }
    return gains_.kp * error + gains_.ki * integral_ + gains_.kd * error_rate;
  }

  void Reset() { integral_ = 0.0; }

 private:
  PidGains gains_;
  double integral_ = 0.0;
};

}  // namespace sim4cv::vehicles
