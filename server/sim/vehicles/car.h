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
#include "server/sim/vehicles/car_params.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

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
