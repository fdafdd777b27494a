// Moving cars: kinematic, on the lanes' centre lines, with the Intelligent
// Driver Model (Treiber, Hennecke, Helbing 2000) for speed, lights, a
// first-come rule at junctions, and a look-ahead along their own route for
// anything in their way (docs/maps.md, "Traffic").
//
// A step runs in three passes so the order cars are stepped in does not
// matter: Survey (where each car's next junction is, whether a light holds
// it), Decide (from everyone's start-of-step positions: acceleration and how
// far it may go), Move.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "server/common/check.h"
#include "server/sim/traffic/layout_util.h"
#include "server/sim/traffic/traffic_state.h"

namespace sim4cv::traffic {
namespace {

using map::SegmentId;

constexpr double kMaxAcceleration = 2.0;      // m/s^2, speeding up (IDM's a)
constexpr double kComfortDeceleration = 4.0;  // m/s^2, braking as a habit (IDM's b)
constexpr double kStopDeceleration = 6.0;     // a car stops for yellow, red or a yield only if this suffices
constexpr double kMaxDeceleration = 8.0;      // m/s^2, the hardest braking, to keep clear of others
constexpr double kStandingGap = 2.5;          // m bumper to bumper when queued (IDM's s0)
constexpr double kHardGap = 1.0;              // m bumper to bumper a step never closes below
// s of following distance (IDM's T). At least sqrt(2 s0 / a) = 1.58 s, or
// a car closing on a stop line or a standing car overshoots (IDM is then
// under-damped about its standing gap).
constexpr double kHeadway = 1.6;
constexpr double kLateralAcceleration = 2.0;  // m/s^2 in bends: the speed limit of a radius r is sqrt(2 r)
constexpr double kLookAhead = 40.0;           // m along its route that a car looks at
constexpr double kClaimDistance = 25.0;       // m: closer than this to a junction, a car going in claims it
constexpr double kCorridorMargin = 0.3;       // m beyond two half widths: another car is in my lane
constexpr double kWalkerMargin = 0.6;         // m beyond the bodies: a walker is about to be in my lane
constexpr double kTailMargin = 0.5;           // m: a car holds a junction until its tail is this far out
constexpr double kEdgeStop = 0.5;             // m before the junction tile, where a car past the crosswalk gives way
constexpr double kStopSlack = 0.3;            // m past a stop point that still counts as at it
constexpr double kHalfLength = kCarLength / 2;
constexpr double kCarCorridor = kCarWidth + kCorridorMargin;

const map::LaneSegment& SegmentOf(const TrafficPlan& plan, SegmentId id) { return plan.graph().segments()[id]; }

// Straight on twice as often as each turn; a U-turn only where it is the one way on (dead ends).
double TurnWeight(map::Turn turn) {
  switch (turn) {
    case map::Turn::kStraight:
      return 2.0;
    case map::Turn::kRight:
    case map::Turn::kLeft:
      return 1.0;
    case map::Turn::kUTurn:
      return 0.0;
  }
  return 0.0;
}

SegmentId ChooseNext(const TrafficPlan& plan, SegmentId from, uint64_t& rng) {
  const std::vector<SegmentId>& options = SegmentOf(plan, from).successors;
  if (options.size() == 1) return options.front();
  double total = 0;
  for (SegmentId id : options) total += TurnWeight(SegmentOf(plan, id).turn);
  double u = layout::NextUniform(rng) * total;
  for (SegmentId id : options) {
    const double weight = TurnWeight(SegmentOf(plan, id).turn);
    if (u < weight) return id;
    u -= weight;
  }
  return options.front();  // only rounding gets here
}

void SetPose(const TrafficPlan& plan, MovingCar& car, double s) {
  car.lane = plan.graph().At(car.route[0], s);
  car.heading = car.lane.heading;
  const Eigen::Vector2d forward(std::cos(car.heading), std::sin(car.heading));
  car.position = Eigen::Vector3d(car.lane.position.x(), car.lane.position.y(), 0.0);
  car.linear_velocity = Eigen::Vector3d(forward.x(), forward.y(), 0.0) * car.speed;
  car.yaw_rate = SegmentOf(plan, car.route[0]).curve.CurvatureAt(car.lane.s) * car.speed;
}

// How far ahead along the car's route `p` lies, if it is within `corridor`
// of the route's centre line, ahead of the car and within the look-ahead.
std::optional<double> AheadOnRoute(const TrafficPlan& plan, const MovingCar& car, const Eigen::Vector2d& p,
                                   double corridor) {
  double start = -car.lane.s;  // where route[k] starts, from the car's centre
  for (int k = 0; k < kPlannedSegments && start <= kLookAhead; ++k) {
    const map::LaneCurve& curve = SegmentOf(plan, car.route[k]).curve;
    const map::LaneCurve::Nearest nearest = curve.Project(p);
    const double along = start + nearest.s;
    // A projection clamped to a later segment's start is the previous segment's business.
    const bool clamped_to_start = k > 0 && nearest.s <= 0.0;
    if (nearest.distance < corridor && along > 0 && !clamped_to_start) {
      if (along > kLookAhead) return std::nullopt;
      return along;
    }
    start += curve.length();
  }
  return std::nullopt;
}

// Bumper to bumper along `car`'s route to `other`, if any of other's centre
// and bumpers lies in its lane corridor ahead: a car crossing ahead, or
// standing at an angle, reaches into a lane where its centre does not.
std::optional<double> GapTo(const TrafficPlan& plan, const MovingCar& car, const MovingCar& other) {
  const Eigen::Vector2d axis(std::cos(other.heading), std::sin(other.heading));
  const double along = std::cos(other.heading - car.heading), across = std::abs(std::sin(other.heading - car.heading));
  std::optional<double> gap;
  for (double offset : {0.0, kHalfLength, -kHalfLength}) {  // centre, front, rear
    const Eigen::Vector2d point = other.position.head<2>() + axis * offset;
    const std::optional<double> ahead = AheadOnRoute(plan, car, point, kCarCorridor);
    if (!ahead) continue;
    // How far other's body reaches back towards `car` from this point.
    const double reach_back =
        (along >= 0 ? offset + kHalfLength : kHalfLength - offset) * std::abs(along) + kCarWidth / 2 * across;
    gap = std::min(gap.value_or(std::numeric_limits<double>::infinity()), *ahead - kHalfLength - reach_back);
  }
  return gap;
}

// How far ahead along `car`'s route a walker on his way across will cross
// its lane, if he has not crossed it yet (and is walking, not standing at
// the kerb).
std::optional<double> CrossingAhead(const TrafficPlan& plan, const MovingCar& car, const Walker& walker) {
  if (walker.linear_velocity.x() == 0 && walker.linear_velocity.y() == 0) return std::nullopt;
  constexpr double kClear = kCarWidth / 2 + kWalkerRadius + kCorridorMargin;  // walker past the lane by this much
  double start = -car.lane.s;
  for (int k = 0; k < kPlannedSegments && start <= kLookAhead; ++k) {
    for (const TrafficPlan::LaneCrossing& crossing : plan.walk_paths()[walker.path].crossings) {
      const double along = start + crossing.s;
      if (crossing.segment == car.route[k] && along > kHalfLength && along <= kLookAhead &&
          (crossing.path_s - walker.s) * walker.direction > -kClear) {
        return along;
      }
    }
    start += SegmentOf(plan, car.route[k]).length();
  }
  return std::nullopt;
}

// Where a car that is to stop before a junction `to_junction` ahead halts
// (metres its centre may still go): the stop line; over that already, the
// near side of the crosswalk; as a last resort (giving way), the junction
// tile's edge, braking as hard as it may. None if it cannot stop at any of
// them.
std::optional<double> StopPoint(double speed, double to_junction, bool already_stopping, bool last_resort) {
  const double points[] = {to_junction - kStopLineBack - kHalfLength,
                           to_junction - kCrosswalkBack - kCrosswalkHalfWidth - kHalfLength,
                           to_junction - kEdgeStop - kHalfLength};
  for (int i = 0; i < (last_resort ? 3 : 2); ++i) {
    // Deciding to stop takes a comfortable stop; having decided, it may
    // brake harder, and halt within the slack, to keep to it (so it does not
    // change its mind as it creeps up to the point).
    const double deceleration = (i == 2 || already_stopping) ? kMaxDeceleration : kStopDeceleration;
    const double room = std::max(points[i] + (already_stopping ? kStopSlack : 0.0), 0.0);
    if (points[i] > -kStopSlack && speed * speed <= 2 * deceleration * room + 1e-9) {
      return std::max(points[i], speed * speed / (2 * deceleration));
    }
  }
  return std::nullopt;
}

// Slowing for bends: for each bend within the look-ahead that the car is
// too fast for, the constant deceleration that brings it down to the bend's
// limit where the bend begins (or at once, in the bend). Followed, that
// deceleration stays the same, so braking for a bend is smooth.
double BendAcceleration(const TrafficPlan& plan, const MovingCar& car) {
  double acceleration = kMaxAcceleration;
  double start = -car.lane.s;
  const double v = car.speed;
  for (int k = 0; k < kPlannedSegments && start <= kLookAhead; ++k) {
    for (const map::Piece& piece : SegmentOf(plan, car.route[k]).curve.pieces()) {
      const double limit_squared = kLateralAcceleration / std::max(std::abs(piece.curvature), 1e-9);
      if (start + piece.length > 0 && v * v > limit_squared) {
        acceleration = std::min(acceleration, -(v * v - limit_squared) / (2 * std::max(start, 1.0)));
      }
      start += piece.length;
    }
  }
  return acceleration;
}

// IDM's braking term for a gap (bumper to bumper) closing at `closing` m/s.
double Interaction(double speed, double gap, double closing) {
  const double wanted =
      kStandingGap +
      std::max(0.0, speed * kHeadway + speed * closing / (2 * std::sqrt(kMaxAcceleration * kComfortDeceleration)));
  const double ratio = wanted / std::max(gap, 0.1);
  return kMaxAcceleration * ratio * ratio;
}

void Survey(const TrafficPlan& plan, const MovingCar& car, double sim_time, CarStepWork& work) {
  work = CarStepWork{};
  // In a junction, or just out of one with its tail still in it.
  const bool tail_inside =
      car.came_from >= 0 && plan.JunctionOf(car.came_from) >= 0 && car.lane.s < kHalfLength + kTailMargin;
  work.inside = plan.JunctionOf(car.route[0]) >= 0 || tail_inside;
  // The next junction on the route, beyond the one the car may be in.
  SegmentId next = -1;
  double to_next = SegmentOf(plan, car.route[0]).length() - car.lane.s;
  for (int k = 1; k < kPlannedSegments && to_next <= kLookAhead; ++k) {
    if (plan.JunctionOf(car.route[k]) >= 0) {
      next = car.route[k];
      break;
    }
    to_next += SegmentOf(plan, car.route[k]).length();
  }
  bool held = false;
  if (next >= 0) {
    const int light = plan.LightControlling(next);
    // Yellow or red: stop if it still can, comfortably, else go on through.
    if (light >= 0 && plan.SignalAt(static_cast<std::size_t>(light), sim_time) != Signal::kGreen) {
      if (const std::optional<double> at = StopPoint(car.speed, to_next, car.stopping_for == next, false)) {
        held = true;
        work.stop_at = *at;
        work.stopping_for = next;
      }
    }
  }
  if (work.inside) {
    work.junction_segment = tail_inside ? car.came_from : car.route[0];
    work.to_junction = tail_inside ? -car.lane.s - SegmentOf(plan, car.came_from).length() : -car.lane.s;
    work.claims = true;
  } else if (next >= 0) {
    work.junction_segment = next;
    work.to_junction = to_next;
    work.claims = !held && to_next < kClaimDistance;
  }
  if (work.claims) work.claimed_since = car.claimed == work.junction_segment ? car.claimed_since : sim_time;
}

// First come, first served: a car about to enter a junction gives way to
// any car in it, or that claimed it earlier (then: nearer to it), whose lane
// crosses or merges with its own. The order is total, so no two cars wait
// for each other, and a car waiting to turn is not passed for ever.
bool MustYield(const TrafficPlan& plan, const std::vector<CarStepWork>& work, std::size_t me) {
  const CarStepWork& mine = work[me];
  for (std::size_t other = 0; other < work.size(); ++other) {
    const CarStepWork& theirs = work[other];
    if (other == me || !theirs.claims || !plan.Conflict(mine.junction_segment, theirs.junction_segment)) continue;
    if (theirs.inside) return true;
    if (theirs.claimed_since != mine.claimed_since) {
      if (theirs.claimed_since < mine.claimed_since) return true;
      continue;
    }
    if (theirs.to_junction < mine.to_junction || (theirs.to_junction == mine.to_junction && other < me)) return true;
  }
  return false;
}

void Decide(const TrafficPlan& plan, TrafficState& state, std::size_t me, std::span<const Obstacle> obstacles) {
  const MovingCar& car = state.cars[me];
  CarStepWork& work = state.work[me];
  const double v = car.speed;
  if (work.claims && !work.inside && MustYield(plan, state.work, me)) {
    const bool stopping = car.stopping_for == work.junction_segment;
    if (const std::optional<double> at = StopPoint(v, work.to_junction, stopping, true)) {
      work.stop_at = std::min(work.stop_at, *at);
      work.stopping_for = work.junction_segment;
    }  // else it is too close to stop: it goes on
  }
  double braking = 0.0;  // the largest IDM interaction term
  double free = std::numeric_limits<double>::infinity();
  const auto constraint = [&](double gap, double closing, double hard_gap) {
    braking = std::max(braking, Interaction(v, gap, closing));
    free = std::min(free, gap - hard_gap);
  };
  // A stop line is a standing car kStandingGap beyond it, so the queue's head halts at the line.
  if (std::isfinite(work.stop_at)) constraint(work.stop_at + kStandingGap, v, kStandingGap);
  const Eigen::Vector2d here = car.position.head<2>();
  const auto near = [&](const Eigen::Vector2d& p) { return (p - here).norm() <= kLookAhead + kCarLength; };
  for (std::size_t other = 0; other < state.cars.size(); ++other) {
    const MovingCar& them = state.cars[other];
    if (other == me || !near(them.position.head<2>())) continue;
    const std::optional<double> gap = GapTo(plan, car, them);
    if (!gap) continue;
    // Each in the other's way (lanes crossing or merging): the one nearer
    // the meeting point goes first.
    const std::optional<double> their_gap = GapTo(plan, them, car);
    if (their_gap && (*gap < *their_gap || (*gap == *their_gap && me < other))) continue;
    const double their_speed = std::max(0.0, them.speed * std::cos(them.heading - car.heading));
    constraint(*gap, v - their_speed, kHardGap);
  }
  // Walkers: one standing in the lane ahead, and one on a crosswalk ahead
  // who has not yet crossed this car's lane. It stops before the whole
  // crosswalk, not on the walking lines nearer than the walker's.
  for (const Walker& walker : state.walkers) {
    if (!near(walker.position.head<2>())) continue;
    const std::optional<double> ahead =
        AheadOnRoute(plan, car, walker.position.head<2>(), kCarWidth / 2 + kWalkerRadius + kWalkerMargin);
    // One beside the car is not in its way (and turns back rather than walk into it: StepWalker).
    if (ahead && *ahead > kHalfLength)
      constraint(*ahead - kHalfLength - kWalkerRadius - layout::kCrosswalkDepth, v, layout::kCarWalkerGap);
    if (const std::optional<double> crossing = CrossingAhead(plan, car, walker)) {
      constraint(*crossing - kHalfLength - kWalkerRadius - layout::kCrosswalkDepth, v, layout::kCarWalkerGap);
    }
  }
  for (const Obstacle& obstacle : obstacles) {
    const Eigen::Vector2d& there = obstacle.position;
    if (!near(there)) continue;
    if (const std::optional<double> ahead = AheadOnRoute(plan, car, there, kCarCorridor)) {
      constraint(*ahead - kCarLength, v, kHardGap);  // its speed is unknown: taken as standing
    }
  }
  for (const TrafficPlan::RoadObstacle& obstacle : plan.road_obstacles()) {
    if (!near(obstacle.position)) continue;
    if (const std::optional<double> ahead =
            AheadOnRoute(plan, car, obstacle.position, kCarWidth / 2 + obstacle.radius + kCorridorMargin)) {
      constraint(*ahead - kHalfLength - obstacle.radius, v, kHardGap);
    }
  }
  const double ratio = v / car.cruise_speed;
  const double acceleration =
      std::min(kMaxAcceleration * (1 - ratio * ratio * ratio * ratio), BendAcceleration(plan, car)) - braking;
  work.acceleration = std::clamp(acceleration, -kMaxDeceleration, kMaxAcceleration);
  work.free_distance = std::max(0.0, free);
}

void Move(const TrafficPlan& plan, MovingCar& car, const CarStepWork& work, double dt) {
  double speed = std::max(0.0, car.speed + work.acceleration * dt);
  double distance = speed * dt;
  // The look-ahead's hard limit: braking harder than kMaxDeceleration
  // rather than touching what is ahead or crossing a stop line.
  if (distance > work.free_distance) {
    distance = work.free_distance;
    speed = std::min(speed, distance / dt);
  }
  car.acceleration = (speed - car.speed) / dt;
  car.speed = speed;
  car.stopping_for = work.stopping_for;
  car.claimed = work.claims ? work.junction_segment : -1;
  car.claimed_since = work.claimed_since;
  double s = car.lane.s + distance;
  while (s > SegmentOf(plan, car.route[0]).length()) {
    s -= SegmentOf(plan, car.route[0]).length();
    car.came_from = car.route[0];
    std::copy(car.route.begin() + 1, car.route.end(), car.route.begin());
    car.route.back() = ChooseNext(plan, car.route[kPlannedSegments - 2], car.rng_state);
  }
  SetPose(plan, car, s);
}

}  // namespace

MovingCar CarAt(const TrafficPlan& plan, SegmentId segment, double s, double cruise_speed, uint64_t rng_seed,
                double speed) {
  SIM4CV_THROW_UNLESS(std::isfinite(cruise_speed) && cruise_speed > 0,
                      "a moving car's cruise speed " << cruise_speed << " m/s must be > 0");
  SIM4CV_THROW_UNLESS(std::isfinite(speed) && speed >= 0, "a moving car's speed " << speed << " m/s must be >= 0");
  MovingCar car;
  car.route[0] = plan.graph().segment(segment).id;  // throws for a segment the map does not have
  car.rng_state = rng_seed;
  for (int k = 1; k < kPlannedSegments; ++k) car.route[k] = ChooseNext(plan, car.route[k - 1], car.rng_state);
  car.cruise_speed = cruise_speed;
  car.speed = speed;
  SetPose(plan, car, s);
  return car;
}

void detail::StepCars(const TrafficPlan& plan, TrafficState& state, double sim_time, double dt,
                      std::span<const Obstacle> obstacles) {
  if (state.work.size() != state.cars.size()) state.work.resize(state.cars.size());
  for (std::size_t i = 0; i < state.cars.size(); ++i) Survey(plan, state.cars[i], sim_time, state.work[i]);
  for (std::size_t i = 0; i < state.cars.size(); ++i) Decide(plan, state, i, obstacles);
  for (std::size_t i = 0; i < state.cars.size(); ++i) Move(plan, state.cars[i], state.work[i], dt);
}

}  // namespace sim4cv::traffic
