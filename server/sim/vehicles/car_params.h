// What a car is (its parameters) and what its driver asks for, apart from
// its Bullet body (car.h), so the Scene and the renderer know cars without
// depending on the physics engine.
#pragma once

#include <Eigen/Core>

namespace sim4cv::vehicles {

inline constexpr int kWheelCount = 4;  // front left, front right, rear left, rear right

struct CarParams {
  // Chassis: a box; the centre of mass sits `center_of_mass_drop` below its centre.
  double mass = 1200.0;                                  // kg
  Eigen::Vector3d chassis_half_extents{2.25, 0.9, 0.6};  // m (4.5 x 1.8 x 1.2 box)
  double center_of_mass_drop = 0.3;                      // m below the box centre
  // Wheels: axles at +-wheelbase/2, wheels at +-track/2, suspension tops at
  // `suspension_top_z` relative to the box centre.
  double wheelbase = 2.7;                       // m
  double track = 1.6;                           // m
  double suspension_top_z = -0.3;               // m
  double wheel_radius = 0.35;                   // m
  double wheel_width = 0.25;                    // m, for drawing only: ray wheels have no width
  double suspension_rest_length = 0.35;         // m
  double max_suspension_travel = 0.2;           // m, either way from rest
  double suspension_stiffness = 20.0;           // 1/s^2 per wheel, per kg of chassis (Bullet's units)
  double suspension_compression_damping = 2.5;  // 1/s per wheel, per kg of chassis
  double suspension_relaxation_damping = 3.5;   // 1/s per wheel, per kg of chassis
  double max_suspension_force = 12000.0;        // N per wheel
  double friction_slip = 1.2;                   // tyre friction coefficient (Bullet's frictionSlip)
  double roll_influence = 0.1;                  // 0..1: share of side forces that rolls the body
  // Drive.
  double max_engine_force = 4000.0;     // N, at throttle 1, shared by the rear wheels
  double max_reverse_force = 2000.0;    // N, at throttle 1 with reverse
  double max_brake_force = 12000.0;     // N, at brake 1, shared by all wheels
  double hold_speed = 0.1;              // m/s: below it with zero throttle ...
  double hold_brake = 0.5;              // ... at least this brake is applied
  double max_steering_deg = 35.0;       // wheel angle at steering +-1
  double max_steering_rate_deg = 90.0;  // deg/s: the wheels cannot turn faster
  double drag_linear = 50.0;            // N per m/s (rolling resistance, simplified)
  double drag_quadratic = 0.4;          // N per (m/s)^2 (air: 0.5 rho Cd A)
};

// What the driver asks for. Out-of-range values are clamped.
struct CarControls {
  double steering = 0.0;  // -1 full left .. +1 full right (positive turns clockwise seen from above)
  double throttle = 0.0;  // 0 .. 1
  double brake = 0.0;     // 0 .. 1; any brake cuts the engine
  bool reverse = false;   // throttle drives backwards
};

// The static sag: the suspension length at rest, where each wheel carries a
// quarter of the weight and Bullet's spring force per wheel is
// stiffness * compression * chassis mass.
double StaticSuspensionLength(const CarParams& params);

// How high the chassis box's centre stands above flat ground at rest:
// where kinematic cars of the same model (traffic) are drawn.
double BoxCentreHeightAtRest(const CarParams& params);

}  // namespace sim4cv::vehicles
