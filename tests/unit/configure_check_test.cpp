// CheckConfigure: a Configure's fields on their own, before it reaches the
// sim thread. Each bad field is named with its value; good requests pass.
#include "server/session/configure_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "server/common/limits.h"
#include "tests/support/no_warnings.h"

namespace sim4cv::session {
namespace {

void ExpectProblem(const proto::Configure& request, const std::string& part) {
  const std::string problem = CheckConfigure(request);
  EXPECT_NE(problem.find(part), std::string::npos) << "'" << problem << "' lacks '" << part << "'";
}

TEST(ConfigureCheckTest, GoodRequestsPass) {
  proto::Configure spawn;
  spawn.mutable_spawn()->set_kind(proto::ENTITY_KIND_PEDESTRIAN);
  EXPECT_EQ(CheckConfigure(spawn), "");
  proto::Configure load;
  load.mutable_load_map()->set_name("tracking/hard_urban");
  load.mutable_load_map()->mutable_traffic()->set_cars(10);
  EXPECT_EQ(CheckConfigure(load), "");
  proto::Configure query;
  query.mutable_query_road()->set_count(4);
  query.mutable_query_road()->set_step(2);
  EXPECT_EQ(CheckConfigure(query), "");
  for (auto* set : {+[](proto::Configure& c) { c.mutable_reset(); }, +[](proto::Configure& c) { c.mutable_get_world(); },
                    +[](proto::Configure& c) { c.mutable_remove()->set_entity_id(7); }}) {
    proto::Configure request;
    set(request);
    EXPECT_EQ(CheckConfigure(request), "");
  }
}

TEST(ConfigureCheckTest, ConditionsAreNamedWithTheValidChoices) {
  proto::Configure request;
  request.mutable_set_conditions()->set_preset("night");
  request.mutable_set_conditions()->set_hour(0.5);
  request.mutable_set_conditions()->set_quality("fast");
  EXPECT_EQ(CheckConfigure(request), "");
  request.mutable_set_conditions()->set_preset("snow");
  ExpectProblem(request, "SetConditions.preset 'snow' is not a preset; use one of clear_noon, clear_morning");
  request.mutable_set_conditions()->set_preset("");
  request.mutable_set_conditions()->set_hour(24.5);
  ExpectProblem(request, "SetConditions.hour is 24.5; it must be a finite number in [0, 24]");
  request.mutable_set_conditions()->set_hour(std::nan(""));
  ExpectProblem(request, "SetConditions.hour is nan");
  request.mutable_set_conditions()->clear_hour();
  request.mutable_set_conditions()->set_noise_read(51);
  ExpectProblem(request, "SetConditions.noise_read is 51; it must be a finite number in [0, 50]");
  request.mutable_set_conditions()->clear_noise_read();
  request.mutable_set_conditions()->set_noise_shot(std::nan(""));
  ExpectProblem(request, "SetConditions.noise_shot is nan");
  request.mutable_set_conditions()->clear_noise_shot();
  request.mutable_set_conditions()->set_randomize_every_frames(10);
  ExpectProblem(request, "SetConditions.randomize_every_frames is 10 without a randomize_seed");
  request.mutable_set_conditions()->set_randomize_every_frames(0);
  request.mutable_set_conditions()->set_quality("ultra");
  ExpectProblem(request, "SetConditions.quality 'ultra' is not a quality");
}

TEST(ConfigureCheckTest, EachBadFieldIsNamedWithItsValue) {
  ExpectProblem(proto::Configure{}, "carries no request");
  proto::Configure request;
  request.mutable_spawn()->set_kind(proto::ENTITY_KIND_UNSPECIFIED);
  ExpectProblem(request, "Spawn.kind is 0");
  request.mutable_spawn()->set_kind(proto::ENTITY_KIND_UAV);
  request.mutable_spawn()->mutable_position()->set_y(NAN);
  ExpectProblem(request, "Spawn.position.y is nan");

  request.Clear();
  request.mutable_load_map()->set_name("../etc/passwd");
  ExpectProblem(request, "no '..'");
  request.mutable_load_map()->set_name("/abs");
  ExpectProblem(request, "no leading '/'");
  request.mutable_load_map()->set_name("ok");
  request.mutable_load_map()->mutable_traffic()->set_pedestrians(5000);
  ExpectProblem(request, "LoadMap.traffic.pedestrians is 5000");

  request.Clear();
  request.mutable_set_route()->set_entity_id(1);
  ExpectProblem(request, "needs route_name, waypoints or keep_route");
  request.mutable_set_route()->mutable_waypoints()->add_points()->set_x(INFINITY);
  request.mutable_set_route()->mutable_waypoints()->add_points();
  ExpectProblem(request, "SetRoute.waypoints.points[0].x is inf");

  request.Clear();
  request.mutable_command_uav()->mutable_velocity()->mutable_velocity()->set_z(25);
  ExpectProblem(request, "CommandUav.velocity.velocity.z is 25");
  request.mutable_command_uav()->mutable_hold()->mutable_position()->set_z(0.2);
  ExpectProblem(request, "CommandUav.hold.position.z is 0.2");

  request.Clear();
  proto::AddCamera& camera = *request.mutable_add_camera();
  camera.set_name("side");
  camera.set_width(8);
  camera.set_height(120);
  camera.set_fov_y_deg(60);
  ExpectProblem(request, "AddCamera.width is 8");
  camera.set_width(160);
  camera.set_name(std::string(65, 'x'));
  ExpectProblem(request, "AddCamera.name 'xxx");
  ExpectProblem(request, "(65 bytes) is too long; a name has at most 64 bytes (limits::kMaxNameBytes)");

  request.Clear();
  request.mutable_query_road()->set_count(101);
  ExpectProblem(request, "QueryRoad.count is 101");
}

// Repeated fields are refused by their count before anything loops over
// them, and an Error quotes at most a few bytes of what the client sent.
TEST(ConfigureCheckTest, WaypointCountIsRefusedBeforeThePointsAreLookedAt) {
  proto::Configure request;
  auto* points = request.mutable_set_route()->mutable_waypoints()->mutable_points();
  for (int i = 0; i <= limits::kMaxRouteWaypoints; ++i) points->Add()->set_x(NAN);
  const std::string problem = CheckConfigure(request);
  EXPECT_NE(problem.find("SetRoute.waypoints.points has 100001 entries; give 2 to 100000"), std::string::npos) << problem;
  EXPECT_NE(problem.find("limits::kMaxRouteWaypoints"), std::string::npos) << problem;
  points->RemoveLast();
  ExpectProblem(request, "SetRoute.waypoints.points[0].x is nan");
  for (auto& point : *points) point.set_x(1);
  points->Mutable(99999)->set_y(INFINITY);
  ExpectProblem(request, "SetRoute.waypoints.points[99999].y is inf");
  points->Mutable(99999)->set_y(0);
  EXPECT_EQ(CheckConfigure(request), "");
}

TEST(ConfigureCheckTest, EveryNameIsBoundedAndQuotedShort) {
  const std::string huge(1 << 20, 'q');
  const std::vector<std::pair<std::string, std::function<void(proto::Configure&)>>> cases = {
      {"LoadMap.name", [&](proto::Configure& c) { c.mutable_load_map()->set_name(huge); }},
      {"LoadMap.route", [&](proto::Configure& c) { c.mutable_load_map()->set_name("x"), c.mutable_load_map()->set_route(huge); }},
      {"Spawn.name", [&](proto::Configure& c) {
         c.mutable_spawn()->set_kind(proto::ENTITY_KIND_CAR);
         c.mutable_spawn()->set_name(huge);
       }},
      {"SetRoute.route_name", [&](proto::Configure& c) { c.mutable_set_route()->set_route_name(huge); }},
      {"AddCamera.name", [&](proto::Configure& c) { c.mutable_add_camera()->set_name(huge); }},
      {"AddCamera.mounted_on", [&](proto::Configure& c) {
         c.mutable_add_camera()->set_name("cam");
         c.mutable_add_camera()->set_mounted_on(huge);
       }},
      {"RemoveCamera.name", [&](proto::Configure& c) { c.mutable_remove_camera()->set_name(huge); }},
  };
  for (const auto& [field, fill] : cases) {
    proto::Configure request;
    fill(request);
    const std::string problem = CheckConfigure(request);
    EXPECT_EQ(problem.rfind(field + " 'qqq", 0), 0u) << field << ": " << problem;
    EXPECT_NE(problem.find("(1048576 bytes) is too long; a name has at most 64 bytes (limits::kMaxNameBytes)"),
              std::string::npos)
        << problem;
    EXPECT_LT(problem.size(), 256u) << field;
  }
  proto::Configure text;
  text.mutable_load_map()->set_text(std::string(limits::kMaxMapTextBytes + 1, '#'));
  ExpectProblem(text, "LoadMap.text is 1048577 bytes; a map text has at most 1048576 bytes (limits::kMaxMapTextBytes)");
}

}  // namespace
}  // namespace sim4cv::session
