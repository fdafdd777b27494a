// The quadcopter's low-level flight controller (after Sim4CV's "several tuned
// PID controllers ... calculated in substeps"): run once per physics substep,
// it turns a velocity or position command and the measured state into a
// thrust along the body z axis and a body torque. Pure maths, no Bullet.
//
//   position hold:  P on position error (clamped) + the setpoint's velocity
//                   -> desired velocity (its acceleration is fed forward below)
//   altitude:       PID on the altitude error (D on the vertical velocity
//                   error) -> vertical acceleration; thrust = m (g + a_z) / cos(tilt)
//   horizontal:     PID per world axis on the velocity error, plus the drag
//                   at the set velocity and the commanded acceleration ->
//                   horizontal acceleration, rotated into the yaw-aligned
//                   frame and clamped to g tan(max_tilt) -> desired roll and
//                   pitch
//   attitude:       P on the angle error -> body rate setpoint; P on the rate
//                   error -> angular acceleration -> torque (x inertia)
//   yaw:            P on the yaw-rate error (position hold: P on yaw first)
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "server/sim/vehicles/pid.h"
#include "server/sim/vehicles/vehicle_state.h"

namespace sim4cv::vehicles {

struct QuadcopterGains {
  // Triple closed-loop pole at -1.5 rad/s: kp = 3 p^2, ki = p^3, kd = 3 p.
  PidGains altitude{6.75, 3.375, 4.5, 3.0};    // m -> m/s^2 (kd on the vertical velocity error, m/s -> m/s^2)
  double max_altitude_error = 1.5;             // m: larger errors are clamped (a bounded climb rate)
  PidGains velocity{2.5, 0.5, 0.0, 2.0, 0.2};  // m/s -> m/s^2, per horizontal world axis
  double max_tilt_deg = 25.0;                  // the horizontal acceleration is clamped to g tan(this)
  double attitude_kp = 8.0;                    // 1/s: angle error (rad) -> body rate setpoint (rad/s)
  double rate_kp = 30.0;                       // 1/s: roll/pitch rate error -> angular acceleration
  double yaw_rate_kp = 10.0;                   // 1/s: yaw rate error -> angular acceleration
  double position_kp = 0.8;                    // 1/s: position error -> velocity setpoint
  double max_horizontal_speed = 8.0;           // m/s, position hold's velocity setpoint
  double yaw_kp = 2.0;                         // 1/s: yaw error -> yaw rate setpoint (position hold)
  double max_yaw_rate = 2.0;                   // rad/s
};

struct QuadcopterCommand {
  enum class Mode { kVelocity, kPosition };
  // kWorld: velocity x/y along world x/y. kHeading: x along the UAV's
  // heading, y to its left (the yaw-aligned frame). z is always world up.
  enum class Frame { kWorld, kHeading };

  Mode mode = Mode::kVelocity;
  // kVelocity: the velocity to fly. kPosition: the setpoint's own velocity,
  // fed forward (zero for a fixed point; for a moving one it removes the lag
  // of the position loop).
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  // m/s
  Frame frame = Frame::kWorld;                         // of `velocity`, both modes
  double yaw_rate = 0.0;  // rad/s, counter-clockwise; kPosition: fed forward like `velocity`
  // Fed forward in both modes: the acceleration of the velocity or of the
  // moving setpoint (e.g. v^2/r towards the centre of a turn). Same frame.
  Eigen::Vector3d acceleration = Eigen::Vector3d::Zero();  // m/s^2
  Eigen::Vector3d position = Eigen::Vector3d::Zero();      // m, world (kPosition)
  double yaw = 0.0;                                        // rad (kPosition)

  static QuadcopterCommand Velocity(const Eigen::Vector3d& velocity, double yaw_rate = 0.0,
                                    Frame frame = Frame::kWorld) {
    QuadcopterCommand c;
    c.velocity = velocity, c.yaw_rate = yaw_rate, c.frame = frame;
    return c;
  }
  static QuadcopterCommand Hold(const Eigen::Vector3d& position, double yaw,
                                const Eigen::Vector3d& velocity = Eigen::Vector3d::Zero(), double yaw_rate = 0.0,
                                const Eigen::Vector3d& acceleration = Eigen::Vector3d::Zero()) {
    QuadcopterCommand c;
    c.mode = Mode::kPosition, c.position = position, c.yaw = yaw;
    c.velocity = velocity, c.yaw_rate = yaw_rate, c.acceleration = acceleration;
    return c;
  }
};

struct QuadcopterActuation {
  double thrust = 0.0;                                                      // N along body +z, in [0, max_thrust]
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();                         // N m, body frame, clamped per axis
  Eigen::Quaterniond desired_orientation = Eigen::Quaterniond::Identity();  // what the attitude loop aims for
};

// What the controller knows of the airframe: feed-forward terms and limits.
struct QuadcopterModel {
  double mass = 1.5;                          // kg
  Eigen::Vector3d inertia{0.05, 0.05, 0.09};  // kg m^2, principal moments on the body axes
  double drag = 0.0;                          // 1/s: drag acceleration per m/s of velocity
  double max_thrust = 36.8;                   // N
  Eigen::Vector3d max_torque{2.0, 2.0, 0.5};  // N m, per body axis
};

class QuadcopterController {
 public:
  QuadcopterController(const QuadcopterGains& gains, const QuadcopterModel& model);

  // Forgets the integrators and holds the altitude of `state`.
  void Reset(const VehicleState& state);

  QuadcopterActuation Update(const QuadcopterCommand& command, const VehicleState& state, double dt);

  const QuadcopterGains& gains() const { return gains_; }

 private:
  double Thrust(const QuadcopterCommand& command, const VehicleState& state, double dt);
  Eigen::Vector2d HorizontalAcceleration(const QuadcopterCommand& command, const VehicleState& state, double yaw,
                                         double dt);

  QuadcopterGains gains_;
  QuadcopterModel model_;
  Pid altitude_pid_;
  Pid velocity_x_pid_;
  Pid velocity_y_pid_;
  double altitude_reference_ = 0.0;  // m; velocity mode integrates the commanded climb rate into it
  bool tilt_saturated_ = false;      // last step's horizontal acceleration was clamped
};

}  // namespace sim4cv::vehicles
