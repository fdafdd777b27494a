// A four-wheeled car on Bullet's btRaycastVehicle: a box chassis with a
// lowered centre of mass on four ray-cast wheels with spring-damper
// suspension, rear-wheel drive, brakes on all wheels, steered front wheels.
// Parameters and their defaults are documented in docs/vehicles.md.
#pragma once

#include <BulletDynamics/Vehicle/btRaycastVehicle.h>
#include <btBulletDynamicsCommon.h>

#include <Eigen/Core>
#include <memory>

#include "server/sim/vehicles/bullet_body.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

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

class Car {
 public:
  // Spawns the car at rest on flat ground at height `ground_z`, its box centre
  // above `position`, heading `yaw` (rad, counter-clockwise from +x), with the
  // suspension already at its static compression.
  Car(btDiscreteDynamicsWorld& world, const CarParams& params, const Eigen::Vector2d& position, double yaw,
      double ground_z = 0.0);
  ~Car() = default;
  Car(const Car&) = delete;
  Car& operator=(const Car&) = delete;

  void SetControls(const CarControls& controls);
  const CarControls& controls() const { return controls_; }

  // Turns the controls into steering, engine, brake and drag, and applies the
  // wheels' suspension and tyre impulses for the next physics step. Call once
  // before every world.stepSimulation(dt, 0).
  void Update(double dt);

  // Pose and velocity of the chassis box centre (what is drawn).
  VehicleState State() const;
  // Velocity along the body x axis, m/s.
  double ForwardSpeed() const;
  // The front wheels' current angle, rad, positive to the right.
  double steering_angle() const { return steering_angle_; }
  // Wheel 0 front left, 1 front right, 2 rear left, 3 rear right: centre and
  // orientation (x along the steered heading, y along the axle, z up with
  // the body; the wheel's spin is left out).
  Pose WheelPose(int wheel) const;

  // Places the car as the constructor does, at rest, steering centred.
  void Reset(const Eigen::Vector2d& position, double yaw, double ground_z = 0.0);

  const CarParams& params() const { return params_; }
  btRigidBody& chassis() { return chassis_.body(); }

  // How high the chassis box's centre stands above flat ground at rest:
  // where kinematic cars of the same model (traffic) are drawn.
  static double BoxCentreHeightAtRest(const CarParams& params);

 private:
  btTransform SpawnPose(const Eigen::Vector2d& position, double yaw, double ground_z) const;
  Eigen::Vector3d BoxCentreInBody() const { return {0.0, 0.0, params_.center_of_mass_drop}; }
  // Adds the box to the compound (above the centre of mass) and returns the
  // compound, so the chassis body's inertia is computed from the full shape.
  static btCollisionShape& BuildChassisShape(btCompoundShape& compound, btBoxShape& box, const CarParams& params);

  CarParams params_;
  CarControls controls_;
  double steering_angle_ = 0.0;
  btBoxShape box_;
  btCompoundShape compound_;
  BodyInWorld chassis_;
  std::unique_ptr<btVehicleRaycaster> raycaster_;
  btRaycastVehicle vehicle_;  // not a world action: Update() runs it, see there
};

}  // namespace sim4cv::vehicles
