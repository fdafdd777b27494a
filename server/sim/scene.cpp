#include "server/sim/scene.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>

#include "server/common/check.h"
#include "server/common/limits.h"
#include "server/common/regular_file.h"
#include "server/sim/map/map_text.h"
#include "server/sim/vehicles/polyline.h"

namespace sim4cv::sim {

int Scene::FindCamera(const std::string& camera_name) const {
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    if (cameras[i].name == camera_name) return static_cast<int>(i);
  }
  return -1;
}

namespace {

// The tracking camera under the UAV, and the car's first- and third-person views.
void AddStandardCameras(Scene& scene, uint32_t width, uint32_t height, float uav_pitch_deg) {
  SIM4CV_THROW_UNLESS(width > 0 && height > 0, "camera size " << width << "x" << height << " must be positive");
  scene.cameras.push_back({"uav", scene.uav.name, width, height, 60.0f, uav_pitch_deg, true, {0, 0, -0.3}});
  scene.cameras.push_back({"car_front", scene.car.name, width, height, 60.0f, 5.0f, false, {2.35, 0, 0.3}});
  scene.cameras.push_back({"car_chase", scene.car.name, width, height, 60.0f, 15.0f, false, {-9, 0, 3.0}});
}

// Reads exactly `count` numbers from the rest of a line.
std::vector<float> ReadNumbers(std::istringstream& words, std::size_t count, int line_number, const std::string& line) {
  std::vector<float> values;
  std::string token;
  while (words >> token) {
    // strtof, unlike operator>>, reads "inf" and "nan", so they get their own message.
    char* end = nullptr;
    const float value = std::strtof(token.c_str(), &end);
    SIM4CV_THROW_UNLESS(end != token.c_str() && *end == '\0',
                        "scene line " << line_number << " '" << line << "': '" << token << "' is not a number");
    SIM4CV_THROW_UNLESS(std::isfinite(value), "scene line " << line_number << " '" << line << "': number not finite");
    values.push_back(value);
  }
  SIM4CV_THROW_UNLESS(values.size() == count,
                      "scene line " << line_number << " '" << line << "': expected " << count << " numbers");
  return values;
}

void RequirePositive(float value, const char* what, int line_number, const std::string& line) {
  SIM4CV_THROW_UNLESS(value > 0, "scene line " << line_number << " '" << line << "': " << what << " must be > 0");
}

}  // namespace

Scene ParseScene(const std::string& text, uint32_t camera_width, uint32_t camera_height) {
  Scene scene;
  std::istringstream lines(text);
  std::string line;
  int line_number = 0;
  float camera_pitch_deg = 60.0f;
  using Handler = std::function<void(std::istringstream&)>;
  // Each keyword consumes the rest of its line; see docs/scenes.md.
  const std::map<std::string, Handler> handlers = {
      {"scene",
       [&](std::istringstream& w) {
         SIM4CV_THROW_UNLESS(w >> scene.name, "scene line " << line_number << ": scene needs a name");
       }},
      {"ground",
       [&](std::istringstream& w) {
         scene.ground_half_size = ReadNumbers(w, 1, line_number, line)[0];
         RequirePositive(scene.ground_half_size, "ground half size", line_number, line);
       }},
      {"lane_width",
       [&](std::istringstream& w) {
         scene.lane_width = ReadNumbers(w, 1, line_number, line)[0];
         RequirePositive(scene.lane_width, "lane width", line_number, line);
       }},
      {"road",
       [&](std::istringstream& w) {
         const auto v = ReadNumbers(w, 2, line_number, line);
         scene.road_loop.emplace_back(v[0], v[1]);
       }},
      {"building",
       [&](std::istringstream& w) {
         const auto v = ReadNumbers(w, 6, line_number, line);
         BuildingSpec b;
         b.id = kFirstBuildingId + static_cast<uint32_t>(scene.buildings.size());
         b.centre = {v[0], v[1]};
         b.half_size = {v[2], v[3]};
         b.height = v[4];
         b.yaw_deg = v[5];
         RequirePositive(std::min({v[2], v[3], v[4]}), "building size", line_number, line);
         scene.buildings.push_back(b);
       }},
      {"car_speed",
       [&](std::istringstream& w) {
         scene.car.cruise_speed = ReadNumbers(w, 1, line_number, line)[0];
         RequirePositive(scene.car.cruise_speed, "car speed", line_number, line);
       }},
      {"uav_altitude",
       [&](std::istringstream& w) {
         scene.uav.altitude = ReadNumbers(w, 1, line_number, line)[0];
         RequirePositive(scene.uav.altitude, "uav altitude", line_number, line);
       }},
      {"camera_pitch",
       [&](std::istringstream& w) {
         const float pitch = ReadNumbers(w, 1, line_number, line)[0];
         SIM4CV_THROW_UNLESS(pitch > 0 && pitch <= 90,
                             "scene line " << line_number << " '" << line << "': camera pitch must be in (0, 90]");
         camera_pitch_deg = pitch;
       }},
  };
  while (std::getline(lines, line)) {
    ++line_number;
    const auto hash = line.find('#');
    std::istringstream words(line.substr(0, hash));
    std::string keyword;
    if (!(words >> keyword)) continue;
    const auto handler = handlers.find(keyword);
    SIM4CV_THROW_UNLESS(handler != handlers.end(),
                        "scene line " << line_number << ": unknown keyword '" << keyword << "'");
    handler->second(words);
  }
  SIM4CV_THROW_UNLESS(scene.road_loop.size() >= 3, "scene '" << scene.name << "' has " << scene.road_loop.size()
                                                             << " road points; a loop needs at least 3");
  SIM4CV_THROW_UNLESS(scene.buildings.size() < 65535 - kFirstBuildingId, "scene has too many buildings");
  AddStandardCameras(scene, camera_width, camera_height, camera_pitch_deg);
  std::vector<Eigen::Vector2d> road;
  for (const auto& p : scene.road_loop) road.push_back(p.cast<double>());
  // Right-hand traffic: the car drives the lane half a lane to the right of the centre line.
  scene.car_lane = vehicles::OffsetLoop(road, scene.lane_width / 2.0);
  return scene;
}

Scene SceneFromMap(std::shared_ptr<const map::Map> loaded, const std::string& route_name, float car_speed,
                   uint32_t camera_width, uint32_t camera_height) {
  SIM4CV_THROW_UNLESS(car_speed > 0, "car speed " << car_speed << " must be > 0");
  Scene scene;
  SIM4CV_THROW_UNLESS(loaded->objects.size() < 65535 - kFirstBuildingId,
                      "map '" << loaded->name << "' has " << loaded->objects.size() << " objects; at most "
                              << 65535 - kFirstBuildingId - 1 << " fit the instance ids");
  const map::Route* route = nullptr;
  for (const auto& candidate : loaded->routes) {
    if (route_name.empty() ? candidate.closed : candidate.name == route_name) route = &candidate;
    if (route) break;
  }
  SIM4CV_THROW_UNLESS(route, "map '" << loaded->name << "' has no "
                                     << (route_name.empty() ? "closed route" : "route named '" + route_name + "'"));
  SIM4CV_THROW_UNLESS(route->closed, "route '" << route->name << "' of map '" << loaded->name
                                               << "' is open; the target car needs a closed route");
  scene.name = loaded->name;
  scene.ground_half_size = static_cast<float>(loaded->HalfExtent().maxCoeff() + 50.0);
  scene.road_graph = std::make_shared<map::RoadGraph>(*loaded);
  scene.car_lane = scene.road_graph->SampleRoute(*route, 1.0).points;
  scene.map = std::move(loaded);
  scene.car.cruise_speed = car_speed;
  AddStandardCameras(scene, camera_width, camera_height, 60.0f);
  return scene;
}

Scene SceneFromMap(const std::string& map_path, const std::string& route_name, float car_speed, uint32_t camera_width,
                   uint32_t camera_height) {
  Scene scene = SceneFromMap(std::make_shared<const map::Map>(map::LoadMapFile(map_path)), route_name, car_speed,
                             camera_width, camera_height);
  scene.map_path = map_path;
  return scene;
}

traffic::TrafficIds TrafficIdsOf(const Scene& scene) {
  // The map's objects take kFirstBuildingId.. in map order (render::BuildMapDrawables).
  return traffic::IdsFrom(scene.traffic.get(),
                          kFirstBuildingId + static_cast<uint32_t>(scene.map ? scene.map->objects.size() : 0));
}

void AddTraffic(Scene& scene, traffic::TrafficConfig config) {
  const bool wants_entities = config.moving_cars > 0 || config.parked_cars > 0 || config.pedestrians > 0;
  if (!scene.map) {
    SIM4CV_THROW_UNLESS(!wants_entities,
                        "traffic (--traffic-cars, --traffic-parked, --traffic-pedestrians) needs a "
                        "tile map (--map); scene '"
                            << scene.name << "' has none");
    return;
  }
  config.traffic_lights = config.traffic_lights && scene.map->surroundings == map::Surroundings::kUrban;
  if (!wants_entities && !config.traffic_lights) return;
  scene.traffic = std::make_shared<const traffic::TrafficPlan>(*scene.map, *scene.road_graph, config);
  SIM4CV_THROW_UNLESS(TrafficIdsOf(scene).end <= 65535,
                      "map '" << scene.name << "' with this much traffic needs ids up to " << TrafficIdsOf(scene).end
                              << "; the instance mask holds 65535");
}

Scene LoadSceneFile(const std::string& path, uint32_t camera_width, uint32_t camera_height) {
  // A FIFO or device is refused, never waited on (docs/reliability.md, finding 7). Scene files
  // are a few KB; the map text bound is as good a bound as any.
  return ParseScene(ReadRegularFile(path, "scene file", limits::kMaxMapTextBytes, "limits::kMaxMapTextBytes"),
                    camera_width, camera_height);
}

Scene DefaultScene(uint32_t camera_width, uint32_t camera_height) {
  return ParseScene(DefaultSceneText(), camera_width, camera_height);
}

}  // namespace sim4cv::sim
