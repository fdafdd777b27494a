#include "driving/controller.h"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace sim4cv::driving {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMinTurnSpeed = 4.0;            // driving_control.MIN_TURN_SPEED, m/s
constexpr double kBrakePerMetrePerSecond = 0.5;  // driving_control.BRAKE_PER_M_S

// Python's min(a, b) and max(a, b): the first argument unless the second is
// strictly smaller (larger). With a NaN these return the bound where
// std::clamp would return the NaN, so the clamps match driving_control.py's
// `max(lo, min(hi, x))` for every input.
double PyMin(double a, double b) { return b < a ? b : a; }
double PyMax(double a, double b) { return b > a ? b : a; }

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

}  // namespace

Controller::Controller(ControllerParams params) : params_(params) {
  if (params_.max_steering_deg <= 0) {
    throw std::invalid_argument("Controller: max_steering_deg must be positive, got " +
                                Number(params_.max_steering_deg));
  }
  if (!(0 <= params_.t_min && params_.t_min <= params_.t_max && params_.t_max <= 1)) {
    throw std::invalid_argument("Controller: need 0 <= t_min <= t_max <= 1, got " + Number(params_.t_min) + ", " +
                                Number(params_.t_max));
  }
  if (!(params_.slowdown >= 0)) {
    throw std::invalid_argument("Controller: slowdown must be >= 0, got " + Number(params_.slowdown));
  }
  if (!(params_.steer_waypoint >= 1 && params_.steer_waypoint <= 4)) {
    throw std::invalid_argument("Controller: steer_waypoint must be 1 ... 4, got " + Number(params_.steer_waypoint));
  }
  if (!(params_.bend >= 0 && params_.bend <= 1)) {
    throw std::invalid_argument("Controller: bend must be 0 ... 1, got " + Number(params_.bend));
  }
  if (!(params_.bend_limit > 0)) {
    throw std::invalid_argument("Controller: bend_limit must be positive, got " + Number(params_.bend_limit));
  }
}

double Controller::BendShift(const Waypoints& w, double v, double h) const {
  if (std::fabs(w[7]) > params_.bend_limit) return 0.0;
  // driving_control.bend_curvature: Menger curvature of waypoints 1-3, in double as Python computes it.
  const double ax = double(w[2]) - w[0], ay = double(w[3]) - w[1];
  const double bx = double(w[4]) - w[0], by = double(w[5]) - w[1];
  const double cross = ax * by - ay * bx;
  const double cx = double(w[4]) - w[2], cy = double(w[5]) - w[3];
  // sqrt, not hypot: CPython's math.hypot is its own code and may differ from libm's in the last bit.
  const double sides = std::sqrt(ax * ax + ay * ay) * std::sqrt(bx * bx + by * by) * std::sqrt(cx * cx + cy * cy);
  const double kappa = sides == 0 ? 0.0 : 2 * cross / sides;
  return -(params_.bend * kappa * (v * v + h * h) / 2.0);
}

double Controller::Steering(double v1, double h1) const {
  if (v1 <= 0) return static_cast<double>((h1 > 0) - (h1 < 0));
  const double steering = params_.gain * std::atan2(h1, v1) / (params_.max_steering_deg * kPi / 180.0);
  return PyMax(-1.0, PyMin(1.0, steering));
}

double Controller::Throttle(double h4, std::optional<double> speed, std::optional<double> max_speed) const {
  if (speed && max_speed && *speed >= *max_speed) return 0.0;
  return PyMax(params_.t_min, PyMin(params_.t_max, params_.t_max - params_.k * std::fabs(h4)));
}

DriveControls Controller::FromWaypoints(const Waypoints& w, std::optional<double> speed,
                                        std::optional<double> max_speed) const {
  // driving_control.aim_point: waypoint k, or linearly between two for a fraction.
  const int k = static_cast<int>(params_.steer_waypoint) - 1;
  const double f = params_.steer_waypoint - 1 - k;
  double v = w[2 * k], h = w[2 * k + 1];
  if (k < 3 && f != 0) {
    v += f * (static_cast<double>(w[2 * k + 2]) - v);
    h += f * (static_cast<double>(w[2 * k + 3]) - h);
  }
  if (params_.bend != 0) h += BendShift(w, v, h);
  double brake = 0.0;
  if (params_.slowdown != 0 && max_speed) {
    // driving_control.turn_speed_cap, and the brake down to it
    max_speed = PyMax(PyMin(kMinTurnSpeed, *max_speed), *max_speed - params_.slowdown * std::fabs(w[7]));
    if (speed && *speed > *max_speed) brake = PyMin(1.0, kBrakePerMetrePerSecond * (*speed - *max_speed));
  }
  return {Steering(v, h), Throttle(w[7], speed, max_speed), brake};
}

}  // namespace sim4cv::driving
