// Initial traffic, walkers, and the whole step (cars: traffic_cars.cpp).
#include "server/sim/traffic/traffic_state.h"

#include <algorithm>
#include <cmath>

#include "server/common/check.h"
#include "server/sim/traffic/footprint.h"
#include "server/sim/traffic/layout_util.h"

namespace sim4cv::traffic {
namespace {

// A walker lets a car pass unless it could stop for him braking this hard
// after this long.
constexpr double kWalkerYieldDeceleration = 3.0;  // m/s^2
constexpr double kWalkerReaction = 1.0;           // s
// A walker turns back rather than come closer than this to a car's body.
constexpr double kBodyGap = 0.05;  // m

Box2 BodyOf(const MovingCar& car) { return {car.position.head<2>(), car.heading, kCarLength / 2, kCarWidth / 2}; }
Box2 BodyOf(const Obstacle& car) { return {car.position, car.heading, kCarLength / 2, kCarWidth / 2}; }

// Whether a simulated car is on the walking line or could be there within
// the crossing's time: it is not driven by traffic rules (it may not stop
// for a light), so a walker gives way to it whatever the signal says.
bool ObstacleComing(const TrafficPlan::WalkPath& path, const Obstacle& car, double walker_speed) {
  const Eigen::Vector2d unit = (path.end - path.start) / path.length;
  const Eigen::Vector2d to_car = car.position - path.start;
  const double along = std::clamp(to_car.dot(unit), 0.0, path.length);
  const Eigen::Vector2d closest = path.start + unit * along;
  const Eigen::Vector2d forward(std::cos(car.heading), std::sin(car.heading));
  const double distance = (car.position - closest).norm();
  if (DistanceTo(BodyOf(car), closest) < 1.0) return true;  // on the line already
  const bool approaching = forward.dot(closest - car.position) > 0;
  // Where it could be by the time the walker is across, with a car length to spare.
  const double reach = car.speed * (path.length / walker_speed + kWalkerReaction) + kCarLength;
  return approaching && distance < reach;
}

void PlaceWalker(const TrafficPlan& plan, Walker& walker, bool walking) {
  const TrafficPlan::WalkPath& path = plan.walk_paths()[walker.path];
  const Eigen::Vector2d unit = (path.end - path.start) / path.length;
  const Eigen::Vector2d at = path.start + unit * walker.s;
  const Eigen::Vector2d facing = unit * walker.direction;
  walker.position = Eigen::Vector3d(at.x(), at.y(), 0.0);
  walker.heading = std::atan2(facing.y(), facing.x());
  walker.linear_velocity = Eigen::Vector3d(facing.x(), facing.y(), 0.0) * (walking ? walker.speed : 0.0);
}

// Whether `car` is on the walking line, or moving and could not stop
// comfortably (with a second to react) where it stops for walkers: before
// the whole crosswalk, kCarWalkerGap short of the walker.
bool CarComing(const TrafficPlan& plan, const TrafficPlan::WalkPath& path, const MovingCar& car) {
  constexpr double kBodyClear = kCarLength / 2 + kWalkerRadius + 0.5;  // centre to line, where bodies are apart
  const double reach = car.speed > 0
                           ? car.speed * kWalkerReaction + car.speed * car.speed / (2 * kWalkerYieldDeceleration) +
                                 layout::kCrosswalkDepth + layout::kCarWalkerGap
                           : 0.0;
  double start = -car.lane.s;  // where route[k] starts, from the car's centre
  for (map::SegmentId id : car.route) {
    for (const TrafficPlan::LaneCrossing& crossing : path.crossings) {
      const double distance = start + crossing.s;
      if (crossing.segment == id && distance > -kBodyClear && distance < reach + kBodyClear) return true;
    }
    start += plan.graph().segments()[id].length();
  }
  return false;
}

// Walkers step off only where no car is coming, and across a junction's
// arm only while its light is red, with time to get across before it turns
// green (or at the very start of a red too short for anyone to get across in).
bool MayCross(const TrafficPlan& plan, const TrafficPlan::WalkPath& path, const Walker& walker, double sim_time,
              std::span<const MovingCar> cars, std::span<const Obstacle> obstacles) {
  if (std::any_of(obstacles.begin(), obstacles.end(),
                  [&](const Obstacle& car) { return ObstacleComing(path, car, walker.speed); })) {
    return false;
  }
  if (path.light >= 0) {
    const TrafficPlan::SignalPhase phase = plan.PhaseAt(static_cast<std::size_t>(path.light), sim_time);
    if (phase.signal != Signal::kRed) return false;
    const double red_s = plan.cycle_s() - plan.config().green_s - plan.config().yellow_s;
    if (phase.time_left < path.length / walker.speed && phase.time_left < red_s - 1.0) return false;
  }
  return std::none_of(cars.begin(), cars.end(), [&](const MovingCar& car) { return CarComing(plan, path, car); });
}

void StepWalker(const TrafficPlan& plan, Walker& walker, double sim_time, double dt, std::span<const MovingCar> cars,
                std::span<const Obstacle> obstacles) {
  const TrafficPlan::WalkPath& path = plan.walk_paths()[walker.path];
  if (walker.pause_left > 0) {
    walker.pause_left = std::max(0.0, walker.pause_left - dt);
    PlaceWalker(plan, walker, false);
    return;
  }
  const bool at_kerb = walker.direction > 0 ? walker.s <= 0 : walker.s >= path.length;
  if (at_kerb && !MayCross(plan, path, walker, sim_time, cars, obstacles)) {
    PlaceWalker(plan, walker, false);
    return;
  }
  // Never into a car: where the next step would bring it closer to a car's
  // body than kBodyGap, it turns back (a car it stood waiting for might be
  // waiting for it).
  const Eigen::Vector2d unit = (path.end - path.start) / path.length;
  const Eigen::Vector2d here = walker.position.head<2>();
  const Eigen::Vector2d next = here + unit * (walker.direction * walker.speed * dt);
  const auto too_close = [&](const Box2& body) {
    const double gap = DistanceTo(body, next);
    return gap < kWalkerRadius + kBodyGap && gap < DistanceTo(body, here);
  };
  if (std::any_of(cars.begin(), cars.end(), [&](const MovingCar& car) { return too_close(BodyOf(car)); }) ||
      std::any_of(obstacles.begin(), obstacles.end(), [&](const Obstacle& car) { return too_close(BodyOf(car)); })) {
    walker.direction = -walker.direction;
    PlaceWalker(plan, walker, false);
    return;
  }
  walker.s += walker.direction * walker.speed * dt;
  if (walker.s > 0 && walker.s < path.length) {
    PlaceWalker(plan, walker, true);
    return;
  }
  // Across: stand a while on the pavement, turned round to go back.
  walker.s = std::clamp(walker.s, 0.0, path.length);
  walker.direction = -walker.direction;
  walker.pause_left = kMinPause + (kMaxPause - kMinPause) * layout::NextUniform(walker.rng_state);
  PlaceWalker(plan, walker, false);
}

}  // namespace

TrafficState InitialTraffic(const TrafficPlan& plan) {
  TrafficState state;
  state.cars.reserve(plan.car_starts().size());
  for (const TrafficPlan::CarStart& start : plan.car_starts()) {
    state.cars.push_back(CarAt(plan, start.lane.segment, start.lane.s, start.cruise_speed, start.rng_seed));
  }
  state.work.resize(state.cars.size());
  state.walkers.reserve(plan.walker_starts().size());
  for (const TrafficPlan::WalkerStart& start : plan.walker_starts()) {
    Walker walker;
    walker.path = start.path;
    walker.speed = start.speed;
    walker.pause_left = start.pause_s;
    walker.rng_state = start.rng_seed;
    PlaceWalker(plan, walker, false);
    state.walkers.push_back(walker);
  }
  return state;
}

void StepTraffic(const TrafficPlan& plan, TrafficState& state, double sim_time, double dt,
                 std::span<const Obstacle> obstacles) {
  SIM4CV_THROW_UNLESS(std::isfinite(dt) && dt > 0, "traffic step of " << dt << " s: must be > 0");
  // Cars first: they look at the walkers where they stand at the step's start.
  detail::StepCars(plan, state, sim_time, dt, obstacles);
  for (Walker& walker : state.walkers) StepWalker(plan, walker, sim_time, dt, state.cars, obstacles);
}

}  // namespace sim4cv::traffic
