#include "server/session/configure_check.h"

#include <cctype>
#include <cmath>
#include <sstream>
#include <type_traits>

#include "protocol/conditions.h"
#include "server/common/limits.h"
#include "server/common/quoted.h"
#include "server/wire/effects_wire.h"
#include "server/wire/entity_kinds_wire.h"

namespace sim4cv::session {
namespace {

using limits::kMaxNameBytes;
// A map's path under --maps-dir: room for a few folders of names.
constexpr std::size_t kMaxMapNameBytes = 4 * kMaxNameBytes;

// A field's name: a string, or a function that builds it, so that a request
// with 100000 waypoints builds one name only if one of them is bad.
template <typename Field>
std::string NameOf(const Field& field) {
  if constexpr (std::is_invocable_v<const Field&>) {
    return field();
  } else {
    return std::string(field);
  }
}

// Accumulates the first problem found; later checks are skipped, and a
// problem's message is built only when it is the one reported.
class Checker {
 public:
  bool ok() const { return problem_.empty(); }

  template <typename Field>
  Checker& Range(const Field& field, double value, double low, double high) {
    if (ok() && !(std::isfinite(value) && value >= low && value <= high)) {
      std::ostringstream message;
      message << NameOf(field) << " is " << value << "; it must be a finite number in [" << low << ", " << high << "]";
      problem_ = message.str();
    }
    return *this;
  }
  template <typename Field>
  Checker& Finite(const Field& field, double value) {
    return Range(field, value, -1e6, 1e6);
  }
  Checker& Vec(const char* field, const proto::Vec3& v) {
    return Finite([&] { return std::string(field) + ".x"; }, v.x())
        .Finite([&] { return std::string(field) + ".y"; }, v.y())
        .Finite([&] { return std::string(field) + ".z"; }, v.z());
  }
  // `problem`: the message, or a function that builds it.
  template <typename Problem>
  Checker& True(bool condition, const Problem& problem) {
    if (ok() && !condition) problem_ = NameOf(problem);
    return *this;
  }
  // A repeated field's length, checked before anything loops over it.
  Checker& Count(const char* field, int count, int low, int high, const char* limit) {
    return True(count >= low && count <= high, [&] {
      return std::string(field) + " has " + std::to_string(count) + " entries; give " + std::to_string(low) + " to " +
             std::to_string(high) + " (" + limit + ")";
    });
  }
  // Every name a client gives is bounded (limits::kMaxNameBytes): names are
  // kept in the world, logged and echoed in Errors.
  Checker& Name(const char* field, const std::string& value, bool may_be_empty) {
    return True(may_be_empty || !value.empty(), [&] { return std::string(field) + " is empty; give it a name"; })
        .True(value.size() <= kMaxNameBytes, [&] {
          return std::string(field) + " " + Quoted(value) + " is too long; a name has at most " +
                 std::to_string(kMaxNameBytes) + " bytes (limits::kMaxNameBytes)";
        });
  }
  // A path under --maps-dir (OpenMap, SaveMap): '/'-separated parts of
  // letters, digits, '_', '-', '.', none empty or starting with '.', so no
  // part is "..", no path is absolute, and no hidden file is named.
  Checker& MapName(const char* field, const std::string& value) {
    True(!value.empty(), [&] { return std::string(field) + " is empty; give the map a name"; });
    bool fine = value.size() <= kMaxMapNameBytes;
    bool part_start = true;
    std::size_t part_bytes = 0;
    for (char c : value) {
      const bool word = std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
      fine = fine && (word || (c == '.' && !part_start) || (c == '/' && !part_start));
      part_start = c == '/';
      part_bytes = part_start ? 0 : part_bytes + 1;
      fine = fine && part_bytes <= limits::kMaxFileNamePartBytes;
    }
    return True(fine && !part_start, [&] {
      return std::string(field) + " " + Quoted(value) +
             " must be a map's path under the maps folder without '.map', e.g. 'studio/my_town': "
             "parts of letters, digits, '_', '-' and '.' separated by '/', none empty or starting with '.', "
             "at most " +
             std::to_string(kMaxMapNameBytes) + " bytes, a part at most " +
             std::to_string(limits::kMaxFileNamePartBytes) + " (limits::kMaxFileNamePartBytes)";
    });
  }
  Checker& MapText(const char* field, const std::string& text) {
    return True(text.size() <= limits::kMaxMapTextBytes, [&] {
      return std::string(field) + " is " + std::to_string(text.size()) + " bytes; a map text has at most " +
             std::to_string(limits::kMaxMapTextBytes) + " bytes (limits::kMaxMapTextBytes)";
    });
  }
  std::string problem() const { return problem_; }

 private:
  std::string problem_;
};

std::string CheckLoadMap(const proto::LoadMap& load) {
  Checker check;
  check.True(load.source_case() != proto::LoadMap::SOURCE_NOT_SET, "LoadMap needs a map: set name or text");
  if (load.has_name()) {
    const std::string& name = load.name();
    check.Name("LoadMap.name", name, false)
        .True(name.find("..") == std::string::npos && (name.empty() || name.front() != '/'), [&] {
          return "LoadMap.name " + Quoted(name) +
                 " must be a shipped map's name relative to the maps folder, e.g. "
                 "'tracking/hard_urban' (no '..', no leading '/')";
        });
  }
  check.MapText("LoadMap.text", load.text());
  check.Name("LoadMap.route", load.route(), true);
  if (load.has_traffic()) {
    check.Range("LoadMap.traffic.cars", load.traffic().cars(), 0, limits::kMaxTrafficCars)
        .Range("LoadMap.traffic.parked", load.traffic().parked(), 0, limits::kMaxTrafficParked)
        .Range("LoadMap.traffic.pedestrians", load.traffic().pedestrians(), 0, limits::kMaxTrafficPedestrians);
  }
  return check.Range("LoadMap.car_speed", load.car_speed(), 0, 40).problem();
}

std::string CheckGenerateMap(const proto::GenerateMap& generate) {
  const std::string& surroundings = generate.surroundings();
  Checker check;
  check
      .True(generate.width() == 0 || (generate.width() >= 3 && generate.width() <= 24),
            [&] {
              return "GenerateMap.width is " + std::to_string(generate.width()) + "; it must be 3..24 tiles (0: 10)";
            })
      .True(generate.height() == 0 || (generate.height() >= 3 && generate.height() <= 24), [&] {
        return "GenerateMap.height is " + std::to_string(generate.height()) + "; it must be 3..24 tiles (0: 10)";
      });
  if (generate.tile_size() != 0) check.Range("GenerateMap.tile_size", generate.tile_size(), 12, 50);
  if (generate.has_roadside_trees()) check.Range("GenerateMap.roadside_trees", generate.roadside_trees(), 0, 1);
  return check
      .True(surroundings.empty() || surroundings == "desert" || surroundings == "urban",
            [&] { return "GenerateMap.surroundings " + Quoted(surroundings) + " must be 'desert' or 'urban'"; })
      .Name("GenerateMap.name", generate.name(), true)
      .MapText("GenerateMap.layout_text", generate.layout_text())
      .problem();
}

std::string CheckSpawn(const proto::Spawn& spawn) {
  return Checker()
      .True(sim::FindEntityKind(spawn.kind()) != nullptr,
            "Spawn.kind is " + std::to_string(spawn.kind()) + "; use " + wire::EntityKindChoices())
      .Name("Spawn.name", spawn.name(), true)
      .Vec("Spawn.position", spawn.position())
      .Finite("Spawn.yaw_deg", spawn.yaw_deg())
      .problem();
}

std::string CheckSetRoute(const proto::SetRoute& route) {
  Checker check;
  check.True(route.path_case() != proto::SetRoute::PATH_NOT_SET, "SetRoute needs route_name, waypoints or keep_route");
  check.Name("SetRoute.route_name", route.route_name(), true);
  if (route.has_waypoints()) {
    const auto& points = route.waypoints().points();
    check.Count("SetRoute.waypoints.points", points.size(), 2, limits::kMaxRouteWaypoints,
                "limits::kMaxRouteWaypoints");
    for (int i = 0; check.ok() && i < points.size(); ++i) {
      const auto field = [i](const char* axis) {
        return [i, axis] { return "SetRoute.waypoints.points[" + std::to_string(i) + "]." + axis; };
      };
      check.Finite(field("x"), points[i].x()).Finite(field("y"), points[i].y());
    }
  }
  return check.Range("SetRoute.speed", route.speed(), 0, 40).problem();
}

std::string CheckCommandUav(const proto::CommandUav& command) {
  Checker check;
  switch (command.order_case()) {
    case proto::CommandUav::kFollow:
      check.Range("CommandUav.follow.altitude", command.follow().altitude(), 0, 500)
          .Range("CommandUav.follow.pitch_down_deg", command.follow().pitch_down_deg(), 0, 90);
      break;
    case proto::CommandUav::kHold:
      check.Vec("CommandUav.hold.position", command.hold().position())
          .Range("CommandUav.hold.position.z", command.hold().position().z(), 0.5, 1e4)
          .Finite("CommandUav.hold.yaw_deg", command.hold().yaw_deg());
      break;
    case proto::CommandUav::kVelocity: {
      const proto::Vec3& v = command.velocity().velocity();
      check.Range("CommandUav.velocity.velocity.x", v.x(), -20, 20)
          .Range("CommandUav.velocity.velocity.y", v.y(), -20, 20)
          .Range("CommandUav.velocity.velocity.z", v.z(), -20, 20)
          .Range("CommandUav.velocity.yaw_rate_deg", command.velocity().yaw_rate_deg(), -180, 180);
      break;
    }
    case proto::CommandUav::kTrack:
      check.Name("CommandUav.track.camera", command.track().camera(), false)
          .Range("CommandUav.track.distance", command.track().distance(), 0, 500)
          .Range("CommandUav.track.altitude", command.track().altitude(), 0, 500);
      break;
    case proto::CommandUav::ORDER_NOT_SET:
      check.True(false, "CommandUav needs an order: follow, hold, velocity or track");
  }
  return check.problem();
}

std::string CheckAddCamera(const proto::AddCamera& camera) {
  return Checker()
      .Name("AddCamera.name", camera.name(), false)
      .Name("AddCamera.mounted_on", camera.mounted_on(), true)
      .Range("AddCamera.width", camera.width(), 16, limits::kMaxAddedCameraWidth)
      .Range("AddCamera.height", camera.height(), 16, limits::kMaxAddedCameraHeight)
      .Range("AddCamera.fov_y_deg", camera.fov_y_deg(), 10, 150)
      .Range("AddCamera.pitch_down_deg", camera.pitch_down_deg(), -90, 90)
      .Finite("AddCamera.yaw_deg", camera.yaw_deg())
      .Vec("AddCamera.offset", camera.offset())
      .problem();
}

std::string CheckSetCameraPose(const proto::SetCameraPose& pose) {
  return Checker()
      .Name("SetCameraPose.camera", pose.camera(), false)
      .Vec("SetCameraPose.position", pose.position())
      .Range("SetCameraPose.position.z", pose.position().z(), 0.05, 1e4)
      .Finite("SetCameraPose.yaw_deg", pose.yaw_deg())
      .Range("SetCameraPose.pitch_down_deg", pose.pitch_down_deg(), -90, 90)
      .problem();
}

std::string CheckQueryRoad(const proto::QueryRoad& query) {
  Checker check;
  check.Vec("QueryRoad.point", query.point()).Finite("QueryRoad.heading_deg", query.heading_deg());
  check.Range("QueryRoad.count", query.count(), 0, limits::kMaxRoadQueryPoints);
  if (query.count() > 0) check.Range("QueryRoad.step", query.step(), 1e-3, 50);
  check.Name("QueryRoad.route", query.route(), true);
  return check.problem();
}

std::string CheckSetConditions(const proto::SetConditions& request) {
  Checker check;
  check.True(request.preset().empty() || conditions::FindByName(request.preset()).has_value(), [&] {
    return "SetConditions.preset " + Quoted(request.preset()) + " is not a preset; use one of " + conditions::Names();
  });
  if (request.has_hour()) check.Range("SetConditions.hour", request.hour(), conditions::kMinHour, conditions::kMaxHour);
  if (request.has_noise_read())
    check.Range("SetConditions.noise_read", request.noise_read(), 0, conditions::kMaxNoiseRead);
  if (request.has_noise_shot())
    check.Range("SetConditions.noise_shot", request.noise_shot(), 0, conditions::kMaxNoiseShot);
  check.True(request.quality().empty() || conditions::FindQuality(request.quality()).has_value(), [&] {
    return "SetConditions.quality " + Quoted(request.quality()) + " is not a quality; use \"full\" or \"fast\"";
  });
  check.True(request.randomize_every_frames() == 0 || request.randomize_seed() != 0, [&] {
    return "SetConditions.randomize_every_frames is " + std::to_string(request.randomize_every_frames()) +
           " without a randomize_seed; give a non-zero seed or leave it 0";
  });
  return check.problem();
}

// Ranges of the fields present; whether the lens folds depends on the
// coefficients in force too, so the sim thread says (Simulation::SetEffects).
std::string CheckSetEffects(const proto::CameraEffects& request) {
  effects::CameraEffects asked;
  wire::ApplyEffects(request, asked);
  return effects::CheckRanges(asked, false);
}

}  // namespace

std::string CheckConfigure(const proto::Configure& request) {
  using Kind = proto::Configure::RequestCase;
  switch (request.request_case()) {
    case Kind::kLoadMap:
      return CheckLoadMap(request.load_map());
    case Kind::kSpawn:
      return CheckSpawn(request.spawn());
    case Kind::kSetRoute:
      return CheckSetRoute(request.set_route());
    case Kind::kCommandUav:
      return CheckCommandUav(request.command_uav());
    case Kind::kAddCamera:
      return CheckAddCamera(request.add_camera());
    case Kind::kRemoveCamera:
      return Checker().Name("RemoveCamera.name", request.remove_camera().name(), false).problem();
    case Kind::kSetCameraPose:
      return CheckSetCameraPose(request.set_camera_pose());
    case Kind::kQueryRoad:
      return CheckQueryRoad(request.query_road());
    case Kind::kSetConditions:
      return CheckSetConditions(request.set_conditions());
    case Kind::kSetEffects:
      return CheckSetEffects(request.set_effects());
    case Kind::kCheckMap:
      return Checker().MapText("CheckMap.text", request.check_map().text()).problem();
    case Kind::kGenerateMap:
      return CheckGenerateMap(request.generate_map());
    case Kind::kOpenMap:
      return Checker().MapName("OpenMap.name", request.open_map().name()).problem();
    case Kind::kSaveMap:
      return Checker()
          .MapName("SaveMap.name", request.save_map().name())
          .MapText("SaveMap.text", request.save_map().text())
          .problem();
    case Kind::kStartLog:
      return Checker()
          .MapName("StartLog.name", request.start_log().name())
          .Name("StartLog.label", request.start_log().label(), true)
          .problem();
    case Kind::kRemove:
    case Kind::kReset:
    case Kind::kStopLog:
    case Kind::kListMaps:
      return {};
    case Kind::REQUEST_NOT_SET:
      break;
    default:  // a request with a file of its own checks its fields on the sim thread (daemon/configure_request.h)
      return {};
  }
  return "Configure carries no request (empty oneof, or a field number this server does not know)";
}

}  // namespace sim4cv::session
