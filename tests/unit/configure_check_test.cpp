// CheckConfigure: a Configure's fields on their own, before it reaches the
// sim thread. Each bad field is named with its value; good requests pass.
#include "server/session/configure_check.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

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
  ExpectProblem(request, "AddCamera.name is 65 characters long");

  request.Clear();
  request.mutable_query_road()->set_count(101);
  ExpectProblem(request, "QueryRoad.count is 101");
}

}  // namespace
}  // namespace sim4cv::session
