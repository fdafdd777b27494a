// The immutable half of the simulation (after MuJoCo's mjModel): everything a
// loaded map defines and no step changes. State (state.h) holds the rest.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "server/sim/map/map.h"
#include "server/sim/map/road_graph.h"
#include "server/sim/traffic/traffic_ids.h"
#include "server/sim/traffic/traffic_plan.h"
#include "server/sim/vehicles/car_params.h"
#include "server/sim/vehicles/quadcopter_params.h"

namespace sim4cv::sim {

// Ids shared by the protocol (EntityInfo.id), the instance mask and the boxes.
inline constexpr uint32_t kCarEntityId = 1;
inline constexpr uint32_t kUavEntityId = 2;
inline constexpr uint32_t kFirstBuildingId = 100;
// Entities take ids below the first static object's (kFirstBuildingId), so the
// mask's instance ids stay unique: at most this many at once.
inline constexpr uint32_t kMaxEntityId = kFirstBuildingId - 1;


struct BuildingSpec {
  uint32_t id = 0;                  // instance id in the mask
  Eigen::Vector2f centre{0, 0};     // metres
  Eigen::Vector2f half_size{5, 5};  // metres, along the building's own x/y
  float height = 10.0f;             // metres
  float yaw_deg = 0.0f;
};

struct CarSpec {
  std::string name = "car";
  float cruise_speed = 6.0f;   // m/s, the waypoint follower's set speed
  vehicles::CarParams params;  // the btRaycastVehicle model (docs/vehicles.md)
};

struct UavSpec {
  std::string name = "uav";
  float altitude = 15.0f;             // m above the car it follows
  vehicles::QuadcopterParams params;  // the quadcopter model (docs/vehicles.md)
};

struct CameraSpec {
  std::string name;
  std::string mounted_on;  // entity name; empty: fixed in the world, `offset` is its position
  uint32_t width = 320, height = 180;
  float fov_y_deg = 60.0f;
  float pitch_down_deg = 60.0f;  // below the horizon (gimbal) or below the body's x axis (fixed)
  // true: a gimbal holds the pitch whatever the body's roll and pitch, and
  // turns only with its yaw; false: rigidly fixed to the body.
  bool gimbal = true;
  Eigen::Vector3d offset{0.0, 0.0, -0.3};  // mount point in the body frame (x forward, y left, z up), m
  float yaw_deg = 0.0f;                    // fixed mounts: turned left of the body's x axis (a side or rear view)
};

struct Scene {
  std::string name = "default";
  // The map file it was built from, as given (a run log's header records
  // it); empty for a scene file, the built-in scene and map text.
  std::string map_path;
  float ground_half_size = 150.0f;         // metres
  float lane_width = 4.0f;                 // metres; the road has two lanes
  std::vector<Eigen::Vector2f> road_loop;  // closed centre line, in driving order
  std::vector<BuildingSpec> buildings;
  CarSpec car;
  UavSpec uav;
  std::vector<CameraSpec> cameras;
  // The closed lane centre line the target car drives, in driving order.
  std::vector<Eigen::Vector2d> car_lane;
  // Set for scenes built from a tile map (docs/maps.md); road_loop and
  // buildings are then empty and the map's objects stand in for them.
  std::shared_ptr<const map::Map> map;
  std::shared_ptr<const map::RoadGraph> road_graph;
  // Map scenes with traffic (AddTraffic): lights, parked and moving cars,
  // walkers (docs/maps.md, "Traffic"). Null: no traffic.
  std::shared_ptr<const traffic::TrafficPlan> traffic;

  // Index of the camera called `name`, or -1.
  int FindCamera(const std::string& name) const;
};

// Parses the scene text format (docs/scenes.md). Throws std::invalid_argument
// naming the line number and the offending text.
Scene ParseScene(const std::string& text, uint32_t camera_width, uint32_t camera_height);

// A scene on a tile map: the target car drives the map's closed route
// `route_name` (empty: the first closed route) at `car_speed`, the camera UAV
// follows it. Throws std::invalid_argument naming the file or route.
Scene SceneFromMap(const std::string& map_path, const std::string& route_name, float car_speed, uint32_t camera_width,
                   uint32_t camera_height);

// The same for a map already loaded (or parsed from a client's text).
Scene SceneFromMap(std::shared_ptr<const map::Map> map, const std::string& route_name, float car_speed,
                   uint32_t camera_width, uint32_t camera_height);

// The ids of the scene's traffic (traffic_ids.h), after the map's objects.
traffic::TrafficIds TrafficIdsOf(const Scene& scene);

// Lays out traffic on a map scene (see TrafficConfig; traffic_lights applies
// to urban maps only: desert maps are road only, as in the paper). Does
// nothing when the config asks for no traffic. Throws std::invalid_argument
// naming the flag and value the map cannot hold, or if the scene has no map
// but traffic is asked for.
void AddTraffic(Scene& scene, traffic::TrafficConfig config);

// Reads and parses a scene file.
Scene LoadSceneFile(const std::string& path, uint32_t camera_width, uint32_t camera_height);

// The scene compiled into the daemon, used when no --scene is given.
Scene DefaultScene(uint32_t camera_width, uint32_t camera_height);

// The text of the embedded default scene (also a worked example of the format).
const std::string& DefaultSceneText();

}  // namespace sim4cv::sim
