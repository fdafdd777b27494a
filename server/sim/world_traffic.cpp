// The World's side of a map's traffic (server/sim/traffic): stepping it with
// the simulated cars as obstacles, and slowing those cars for it.
#include <algorithm>
#include <cmath>

#include "server/sim/world.h"

namespace sim4cv::sim {
namespace {

// How often the map's traffic is stepped, Hz (at most the physics rate).
constexpr double kTrafficHz = 60.0;

}  // namespace

void World::StepTraffic(State& state, double dt) {
  if (!scene_.traffic) return;
  // Kinematic traffic needs no 240 Hz: it steps at about kTrafficHz, every
  // `every`-th physics step, by that many steps' time (fixed, so runs stay
  // bit-identical). Its cost is then a quarter, and frames at 30 Hz see it
  // move smoothly.
  const auto every = static_cast<uint64_t>(std::max(1L, std::lround(1.0 / (kTrafficHz * dt))));
  if (state.physics_steps % every != 0) return;
  dt *= static_cast<double>(every);
  obstacles_.clear();
  // Spawned pedestrians count as well: traffic cars stop for them, and
  // walkers keep off them.
  for (const Entity& entity : state.entities) {
    if (entity.kind == EntityKind::kUav) continue;
    const double yaw = entity.body.Yaw();
    const double speed = entity.body.linear_velocity.head<2>().dot(Eigen::Vector2d(std::cos(yaw), std::sin(yaw)));
    obstacles_.push_back({entity.body.position.head<2>(), yaw, std::max(0.0, speed)});
  }
  traffic::StepTraffic(*scene_.traffic, state.traffic, state.sim_time, dt, obstacles_);
}

bool World::AnythingToGiveWayTo(const State& state) const {
  if (scene_.traffic) return true;
  int others = 0;  // cars and pedestrians; one car alone has nobody to meet
  for (const Entity& entity : state.entities) others += entity.kind != EntityKind::kUav ? 1 : 0;
  return others > 1;
}

double World::SpeedForTraffic(const State& state, const Entity& car, const vehicles::Polyline& path) const {
  // Something on the car's own path ahead (within a car's half width plus
  // the other's of it) is treated as standing: stop `standoff` metres behind
  // it (centre to centre) with a gentle 3 m/s^2, planning from where it is
  // now. Measured along the path, so a car round a bend ahead counts too.
  constexpr double kLookAhead = 35.0, kDeceleration = 3.0;
  const Eigen::Vector2d from = car.body.position.head<2>();
  const double s_car = path.Project(from).arc_length;
  double gap = kLookAhead;
  const auto consider = [&](const Eigen::Vector2d& p, double half_corridor, double standoff) {
    if ((p - from).squaredNorm() > kLookAhead * kLookAhead) return;
    const vehicles::Polyline::Projection on_path = path.ProjectNear(p, s_car, kLookAhead + 5.0);
    if (on_path.distance > half_corridor) return;
    double ahead = on_path.arc_length - s_car;
    if (path.closed() && ahead < -path.length() / 2) ahead += path.length();
    if (ahead > 0 && ahead < kLookAhead) gap = std::min(gap, ahead - standoff);
  };
  for (const traffic::MovingCar& other : state.traffic.cars) consider(other.position.head<2>(), 1.8, 6.0);
  // The other simulated cars and the spawned pedestrians, likewise.
  for (const Entity& other : state.entities) {
    if (other.id == car.id || other.kind == EntityKind::kUav) continue;
    const bool walking = other.body.linear_velocity.squaredNorm() > 0.0;
    if (other.kind == EntityKind::kCar) {
      consider(other.body.position.head<2>(), 1.8, 6.0);
    } else {
      consider(other.body.position.head<2>(), walking ? 2.2 : 1.2, 4.0);
    }
  }
  // A walker on the move may step into the lane: keep a wide berth. One
  // standing at the kerb waits for this very car to pass (it gives way to
  // simulated cars), so only one standing in the lane stops it.
  for (const traffic::Walker& walker : state.traffic.walkers) {
    const bool walking = walker.linear_velocity.squaredNorm() > 0.0;
    consider(walker.position.head<2>(), walking ? 2.2 : 1.2, 4.0);
  }
  const double cruise = car.cruise_speed;
  if (gap >= kLookAhead) return cruise;
  return std::min<double>(cruise, std::sqrt(2.0 * kDeceleration * std::max(0.0, gap)));
}

}  // namespace sim4cv::sim
