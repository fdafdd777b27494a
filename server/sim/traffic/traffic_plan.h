// The immutable half of traffic (after MuJoCo's mjModel; the mutable half is
// traffic_state.h): built once from a map, it says where traffic lights
// stand and which lanes they hold, how each junction's cycle runs, where the
// crosswalks are, where cars are parked, and where moving cars and walkers
// start. docs/maps.md, "Traffic", describes the layout and every parameter.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "server/sim/map/map.h"
#include "server/sim/map/prng.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/traffic/signal.h"
#include "server/sim/traffic/traffic_config.h"

namespace sim4cv::traffic {

class TrafficPlan {
 public:
  using Signal = traffic::Signal;

  // A T-junction or crossroads tile; its lights share one cycle.
  struct Junction {
    map::TileCoord tile;
    double phase_s = 0.0;  // how far into its cycle the junction is at sim_time 0, in [0, cycle_s)
  };

  // One per arm of a junction, at the kerb on the right of the traffic
  // coming in, kLightLateral off the road's centre line and about
  // kLightBack before the junction tile.
  struct Light {
    Eigen::Vector2d position{0, 0};       // the pole's foot (z = 0)
    double heading = 0.0;                 // where the lamps face: back along the arm, at the traffic coming in
    int junction = 0;                     // index into junctions()
    map::Edge entry = map::Edge::kNorth;  // the junction tile's side that traffic enters through
    int axis = 0;                         // 0: entry north or south; 1: east or west. The axes alternate.
    // The junction's straight-on segment entering through `entry` (its first
    // one where there is none). Every segment entering there is held: see
    // LightControlling.
    map::SegmentId controls = -1;
  };

  // Where a lane's centre line crosses a walking line.
  struct LaneCrossing {
    map::SegmentId segment = -1;
    double s = 0.0;       // arc length along the segment
    double path_s = 0.0;  // and along the walking line, from its start
  };
  // A walking line across the road; a walker goes start -> end -> start ...
  struct WalkPath {
    Eigen::Vector2d start{0, 0}, end{0, 0};  // on the pavements, at most kCrosswalkReach off the centre line
    double length = 0.0;
    // The light of the junction arm it crosses: walkers set off only while
    // it is red. -1 without lights or for a crosswalk in mid-block.
    int light = -1;
    // Every lane it crosses: a walker checks them for cars coming, a car for
    // walkers about to cross its lane.
    std::vector<LaneCrossing> crossings;
  };

  // Where a crosswalk crosses the road (its kWalkLines walking lines run
  // side by side across it): what the road's zebra markings are drawn from.
  struct Crosswalk {
    Eigen::Vector2d middle{0, 0};  // on the road's centre line
    Eigen::Vector2d across{0, 0};  // unit, across the road
    Eigen::Vector2d along{0, 0};   // unit, along the road
  };

  // A static obstacle that reaches into the lanes: an object of the map
  // standing on the road. Moving cars stop behind it.
  struct RoadObstacle {
    Eigen::Vector2d position{0, 0};
    double radius = 0.0;  // its base radius (ShapeOf)
  };

  struct CarStart {
    map::LanePoint lane;
    double cruise_speed = 0.0;  // m/s, in [kMinCruiseSpeed, kMaxCruiseSpeed]
    uint64_t rng_seed = 0;      // the car's own stream for turns at junctions
  };
  struct WalkerStart {
    int path = 0;           // index into walk_paths(); every walker has its own
    double speed = 0.0;     // m/s, in [kMinWalkSpeed, kMaxWalkSpeed]
    double pause_s = 0.0;   // it first stands this long at the start of its path
    uint64_t rng_seed = 0;  // the walker's own stream for its pauses
  };

  struct SignalPhase {
    Signal signal = Signal::kRed;
    double time_left = 0.0;  // seconds until the signal changes (red: until it turns green)
  };

  // Throws std::invalid_argument naming the flag and value when `config`
  // cannot be met, e.g. "--traffic-cars 500: the map's lanes hold at most 37 cars".
  // Keeps its own copy of the road graph.
  TrafficPlan(const map::Map& map, const map::RoadGraph& graph, const TrafficConfig& config);

  const TrafficConfig& config() const { return config_; }
  const map::RoadGraph& graph() const { return graph_; }
  const std::vector<Junction>& junctions() const { return junctions_; }
  const std::vector<Light>& lights() const { return lights_; }
  const std::vector<WalkPath>& walk_paths() const { return walk_paths_; }
  const std::vector<Crosswalk>& crosswalks() const { return crosswalks_; }
  const std::vector<Pose2>& parked_cars() const { return parked_cars_; }
  const std::vector<RoadObstacle>& road_obstacles() const { return road_obstacles_; }
  const std::vector<CarStart>& car_starts() const { return car_starts_; }
  const std::vector<WalkerStart>& walker_starts() const { return walker_starts_; }
  // How many the map has room for (what the config is checked against).
  int moving_car_capacity() const { return moving_car_capacity_; }
  int parked_car_capacity() const { return parked_car_capacity_; }
  int pedestrian_capacity() const { return static_cast<int>(walk_paths_.size()); }

  // A junction's cycle: green, yellow, all-red for axis 0, then the same for axis 1.
  double cycle_s() const { return 2 * (config_.green_s + config_.yellow_s + config_.all_red_s); }
  // Pure functions of time (seconds): the same time always gives the same signal.
  Signal SignalAt(std::size_t light, double sim_time) const { return PhaseAt(light, sim_time).signal; }
  SignalPhase PhaseAt(std::size_t light, double sim_time) const;

  // The light that holds traffic entering `segment` (a junction's segment), or -1.
  int LightControlling(map::SegmentId segment) const { return light_of_segment_[segment]; }
  // The junction `segment` runs through, or -1.
  int JunctionOf(map::SegmentId segment) const { return junction_of_segment_[segment]; }
  // Whether two segments of one junction, entering through different sides,
  // come close enough that two cars on them could touch.
  bool Conflict(map::SegmentId a, map::SegmentId b) const;

 private:
  void CheckConfig() const;
  void PlaceJunctions(const map::Map& map, map::Prng& rng);
  Light MakeLight(const map::Map& map, int junction, map::Edge entry) const;
  void FindConflicts(const std::vector<map::SegmentId>& tile_segments);
  void PlaceCrosswalks(const map::Map& map);
  void AddCrosswalk(const map::Map& map, const Eigen::Vector2d& centre, const Eigen::Vector2d& across,
                    const Eigen::Vector2d& along, int light);
  std::vector<LaneCrossing> FindCrossings(const Eigen::Vector2d& start, const Eigen::Vector2d& end) const;
  void FindRoadObstacles(const map::Map& map);
  std::vector<Pose2> FindKerbSlots(const map::Map& map) const;
  std::vector<map::LanePoint> FindStartSlots() const;
  void ChooseStarts(const map::Map& map);

  TrafficConfig config_;
  map::RoadGraph graph_;
  std::vector<Junction> junctions_;
  std::vector<Light> lights_;
  std::vector<WalkPath> walk_paths_;
  std::vector<Crosswalk> crosswalks_;
  std::vector<Pose2> parked_cars_;
  std::vector<RoadObstacle> road_obstacles_;
  std::vector<CarStart> car_starts_;
  std::vector<WalkerStart> walker_starts_;
  int moving_car_capacity_ = 0, parked_car_capacity_ = 0;
  // Per segment: the light holding entry into it, its junction, the first
  // segment id of its tile, and a bit per segment of the tile it conflicts with.
  std::vector<int> light_of_segment_, junction_of_segment_;
  std::vector<map::SegmentId> first_in_tile_;
  std::vector<uint16_t> conflicts_;
};

}  // namespace sim4cv::traffic
