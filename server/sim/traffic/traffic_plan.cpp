#include "server/sim/traffic/traffic_plan.h"

#include <cmath>

#include "server/common/check.h"
#include "server/sim/traffic/layout_util.h"

namespace sim4cv::traffic {

TrafficPlan::TrafficPlan(const map::Map& map, const map::RoadGraph& graph, const TrafficConfig& config)
    : config_(config), graph_(graph) {
  CheckConfig();
  map::Prng junction_rng = layout::Stream(config_.seed, layout::kJunctionStream);
  PlaceJunctions(map, junction_rng);
  PlaceCrosswalks(map);
  FindRoadObstacles(map);
  ChooseStarts(map);
}

void TrafficPlan::CheckConfig() const {
  SIM4CV_THROW_UNLESS(config_.moving_cars >= 0, "--traffic-cars " << config_.moving_cars << ": must be >= 0");
  SIM4CV_THROW_UNLESS(config_.parked_cars >= 0, "--traffic-parked " << config_.parked_cars << ": must be >= 0");
  SIM4CV_THROW_UNLESS(config_.pedestrians >= 0, "--traffic-pedestrians " << config_.pedestrians << ": must be >= 0");
  SIM4CV_THROW_UNLESS(std::isfinite(config_.green_s) && config_.green_s > 0,
                      "--traffic-green " << config_.green_s << ": must be a time > 0 s");
  SIM4CV_THROW_UNLESS(std::isfinite(config_.yellow_s) && config_.yellow_s >= 0,
                      "--traffic-yellow " << config_.yellow_s << ": must be a time >= 0 s");
  SIM4CV_THROW_UNLESS(std::isfinite(config_.all_red_s) && config_.all_red_s >= 0,
                      "--traffic-all-red " << config_.all_red_s << ": must be a time >= 0 s");
}

void TrafficPlan::ChooseStarts(const map::Map& map) {
  const std::vector<Pose2> kerb = FindKerbSlots(map);
  parked_car_capacity_ = static_cast<int>(kerb.size());
  SIM4CV_THROW_UNLESS(config_.parked_cars <= parked_car_capacity_,
                      "--traffic-parked " << config_.parked_cars << ": the map's kerbs hold at most "
                                          << parked_car_capacity_ << " parked cars");
  map::Prng parked_rng = layout::Stream(config_.seed, layout::kParkedStream);
  for (int i : layout::Choose(parked_car_capacity_, config_.parked_cars, parked_rng)) parked_cars_.push_back(kerb[i]);

  const std::vector<map::LanePoint> lanes = FindStartSlots();
  moving_car_capacity_ = static_cast<int>(lanes.size());
  SIM4CV_THROW_UNLESS(
      config_.moving_cars <= moving_car_capacity_,
      "--traffic-cars " << config_.moving_cars << ": the map's lanes hold at most " << moving_car_capacity_ << " cars");
  map::Prng car_rng = layout::Stream(config_.seed, layout::kCarStream);
  for (int i : layout::Choose(moving_car_capacity_, config_.moving_cars, car_rng)) {
    CarStart start;
    start.lane = lanes[i];
    start.cruise_speed = car_rng.Uniform(kMinCruiseSpeed, kMaxCruiseSpeed);
    start.rng_seed = car_rng.Next();
    car_starts_.push_back(start);
  }

  SIM4CV_THROW_UNLESS(config_.pedestrians <= pedestrian_capacity(),
                      "--traffic-pedestrians " << config_.pedestrians << ": the map's crosswalks hold at most "
                                               << pedestrian_capacity() << " walkers (one per walking line)");
  map::Prng walker_rng = layout::Stream(config_.seed, layout::kWalkerStream);
  for (int path : layout::Choose(pedestrian_capacity(), config_.pedestrians, walker_rng)) {
    WalkerStart start;
    start.path = path;
    start.speed = walker_rng.Uniform(kMinWalkSpeed, kMaxWalkSpeed);
    start.pause_s = walker_rng.Uniform(0, kMaxPause);  // so walkers do not all step off together
    start.rng_seed = walker_rng.Next();
    walker_starts_.push_back(start);
  }
}

TrafficPlan::SignalPhase TrafficPlan::PhaseAt(std::size_t light, double sim_time) const {
  SIM4CV_THROW_UNLESS(light < lights_.size(),
                      "no traffic light " << light << " (the plan has " << lights_.size() << ")");
  const Light& l = lights_[light];
  const double cycle = cycle_s();
  const double half = cycle / 2;
  // Where this light's axis is in its own green-yellow-red cycle; axis 1
  // runs half a cycle behind axis 0, so its green falls in axis 0's red.
  double u = std::fmod(sim_time + junctions_[l.junction].phase_s - (l.axis == 1 ? half : 0.0), cycle);
  if (u < 0) u += cycle;
  const double green = config_.green_s, yellow_end = config_.green_s + config_.yellow_s;
  if (u < green) return {Signal::kGreen, green - u};
  if (u < yellow_end) return {Signal::kYellow, yellow_end - u};
  return {Signal::kRed, cycle - u};
}

}  // namespace sim4cv::traffic
