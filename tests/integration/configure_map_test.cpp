// Configure against the real daemon: loading maps (by name, as text, refused
// ones), routes and speeds for spawned cars, road queries, and requests the
// network thread refuses at once for a bad field.
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <set>

#include "tests/support/configure_fixture.h"

namespace sim4cv::testing {
namespace {

using namespace std::chrono_literals;

constexpr uint32_t kCarId = 1;
constexpr char kDesert[] = "tracking/easy_desert";

class MapTest : public ConfigureTest {
 protected:
  void SetUp() override {
    StartDaemon();
    client_ = Connect("configure");
  }

  // The entity's position after `frames` more frames.
  proto::Vec3 PositionAfter(int frames, uint32_t id) {
    const proto::Frame& frame = StepFrames(*client_, frames);
    const proto::EntityState* entity = FindEntity(frame.state(), id);
    EXPECT_NE(entity, nullptr) << "entity " << id << " is not in frame " << frame.frame_id();
    return entity ? entity->position() : proto::Vec3{};
  }

  std::unique_ptr<Client> client_;
};

TEST_F(MapTest, LoadMapByNameSwitchesTheSceneAndKeepsTheUavSubscription) {
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  EXPECT_EQ(StepFrames(*client_, 10).frame_id(), 10u);

  const proto::WorldInfo world = client_->LoadMapByName(kDesert, "", 8);
  EXPECT_EQ(world.scene_name(), "tracking_easy_desert");
  ASSERT_EQ(world.routes_size(), 1);
  EXPECT_EQ(world.routes(0), "loop");
  EXPECT_EQ(world.frame_id(), 0u);
  EXPECT_EQ(Connect("late")->welcome().scene_name(), "tracking_easy_desert");

  // The same subscription goes on, in the new world from its frame 1.
  const proto::State start = client_->GetState();
  for (uint64_t id = 1; id <= 150; ++id) {  // 5 s
    const proto::Frame& frame = client_->StepAndReceive();
    ASSERT_EQ(frame.frame_id(), id);
    EXPECT_TRUE(BoxOf(frame, kCarId).has_value()) << "the UAV films the map's car, frame " << id;
  }
  const proto::State later = client_->GetState();
  EXPECT_NEAR(std::hypot(later.entities(0).linear_velocity().x(), later.entities(0).linear_velocity().y()), 8.0, 1.5)
      << "LoadMap.car_speed 8";
  EXPECT_GT(PlaneDistance(later.entities(0).position(), start.entities(0).position()), 5.0);
}

// A map loaded with traffic settings gets that traffic, whatever the
// daemon's flags: the chase camera behind the target car sees pedestrians
// and traffic lights; more than the map holds is refused naming the field.
TEST_F(MapTest, LoadMapWithTrafficSettings) {
  client_->Subscribe("car_front", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP);
  proto::TrafficSettings traffic;
  traffic.set_cars(10);
  traffic.set_parked(20);
  traffic.set_pedestrians(40);
  client_->LoadMapByName("driving/train/01_urban", "", 6, traffic);
  std::set<int> classes;
  for (int frame = 0; frame < 150; ++frame) {
    for (const proto::Box& box : StepFrames(*client_, 1).boxes()) classes.insert(box.object_class());
  }
  for (const int wanted : {proto::OBJECT_CLASS_CAR, proto::OBJECT_CLASS_PEDESTRIAN, proto::OBJECT_CLASS_TRAFFIC_LIGHT}) {
    EXPECT_TRUE(classes.count(wanted)) << proto::ObjectClass_Name(wanted) << " never seen";
  }
  traffic.set_cars(400);
  ExpectRefused([&] { client_->LoadMapByName("driving/train/01_urban", "", 6, traffic); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"LoadMap.traffic", "400", "138"});
}

TEST_F(MapTest, LoadMapAsTextAndRefusedMaps) {
  const proto::WorldInfo tiny = client_->LoadMapText(
      "sim4cv-map 1\nname tiny\ntile_size 20\ngrid 3 3\n###\n#.#\n###\nend\n"
      "route ring closed\ntiles 0,0 0,1 0,2 1,2 2,2 2,1 2,0 1,0\n");
  EXPECT_EQ(tiny.scene_name(), "tiny");
  ASSERT_EQ(tiny.routes_size(), 1);
  EXPECT_EQ(tiny.routes(0), "ring");

  ExpectRefused([&] { client_->LoadMapText("sim4cv-map 1\nname broken\ncolour red\n"); },
                proto::ERROR_CODE_INVALID_ARGUMENT, {"LoadMap.text", "line 3", "colour"});
  ExpectRefused([&] { client_->LoadMapByName("../../etc/passwd"); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"'../../etc/passwd'", "'..'"});
  ExpectRefused([&] { client_->LoadMapByName("tracking/no_such_map"); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"'tracking/no_such_map'", "no such map"});
  ExpectRefused([&] { client_->LoadMapByName(kDesert, "nowhere"); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"'nowhere'"});
  EXPECT_EQ(client_->GetWorld().scene_name(), "tiny") << "a refused LoadMap changes nothing";
}

// A log holds one map, and its frame ids must increase: neither LoadMap nor
// Reset may break it.
TEST_F(MapTest, LoadMapAndResetAreRefusedWhileTheDaemonWritesARunLog) {
  const std::string log = "/tmp/sim4cv-configure-" + std::to_string(getpid()) + ".s4log";
  daemon_->Stop();
  StartDaemon({"--log", log});
  client_ = Connect("logged");
  ExpectRefused([&] { client_->LoadMapByName(kDesert); }, proto::ERROR_CODE_INVALID_STATE, {"--log", log});
  ExpectRefused([&] { client_->Reset(); }, proto::ERROR_CODE_INVALID_STATE, {"Reset", "--log", log});
  EXPECT_EQ(client_->GetWorld().scene_name(), "default");
  std::filesystem::remove(log);  // the daemon writes on into the unlinked file
}

TEST_F(MapTest, SpawnedCarDrivesAMapRouteUntilItsSpeedIsZero) {
  const proto::WorldInfo world = client_->LoadMapByName(kDesert);
  ASSERT_GT(world.routes_size(), 0);
  client_->Subscribe("uav", {proto::CHANNEL_BOXES}, proto::DELIVERY_LOCKSTEP, /*with_state=*/true);
  // 60 m ahead of the target car on its lane, turned the wrong way: snapping
  // puts the new car on the lane centre, facing along it.
  const proto::Vec3 target = client_->GetState().entities(0).position();
  const proto::RoadQueryResult road = client_->QueryRoad(target.x(), target.y(), 2, 30);
  ASSERT_EQ(road.ahead_size(), 2);
  const proto::LanePoint& spot = road.ahead(1);
  const uint32_t car = client_->Spawn(proto::ENTITY_KIND_CAR, "car_b", spot.position().x() + 1.0,
                                      spot.position().y() + 1.0, 0, spot.heading_deg() + 150, /*snap_to_lane=*/true);
  const proto::Vec3 start = PositionAfter(1, car);
  const proto::RoadQueryResult on_lane = client_->QueryRoad(start.x(), start.y());
  EXPECT_LT(on_lane.distance(), 0.1) << "snapped onto the lane centre";

  ExpectRefused([&] { client_->SetRoute(car, "nowhere", 5); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"'nowhere'", "'" + world.routes(0) + "'"});
  ExpectRefused([&] { client_->SetRoute(99, world.routes(0), 5); }, proto::ERROR_CODE_UNKNOWN_ENTITY, {"99"});
  ExpectRefused([&] { client_->SetSpeed(car, 3); }, proto::ERROR_CODE_INVALID_ARGUMENT, {"no route"});

  client_->SetRoute(car, world.routes(0), 5);
  const proto::Vec3 driven = PositionAfter(150, car);  // 5 s
  EXPECT_GT(PlaneDistance(driven, start), 10.0) << "from " << start.ShortDebugString() << " to "
                                                 << driven.ShortDebugString();
  EXPECT_LT(client_->QueryRoad(driven.x(), driven.y()).distance(), 0.5) << "it keeps to its lane";

  client_->SetSpeed(car, 0);
  const proto::Vec3 braked = PositionAfter(90, car);  // 3 s to stop
  EXPECT_LT(PlaneDistance(PositionAfter(30, car), braked), 0.1) << "it stands still at speed 0";
}

TEST_F(MapTest, QueryRoadFindsTheLaneAndThePointsAhead) {
  ExpectRefused([&] { client_->QueryRoad(0, 0); }, proto::ERROR_CODE_INVALID_STATE, {"needs a map scene", "'default'"});
  client_->LoadMapByName(kDesert);
  const proto::Vec3 car = client_->GetState().entities(0).position();
  const proto::RoadQueryResult at_car = client_->QueryRoad(car.x(), car.y());
  EXPECT_LT(at_car.distance(), 0.05) << "the car starts on its lane centre";
  EXPECT_EQ(at_car.ahead_size(), 0);

  // 1 m left of that lane centre, asking along the lane's heading.
  const double heading = at_car.nearest().heading_deg();
  const double h = heading * std::numbers::pi / 180;
  const double x = at_car.nearest().position().x() - std::sin(h), y = at_car.nearest().position().y() + std::cos(h);
  const proto::RoadQueryResult left = client_->QueryRoad(x, y, 4, 2, heading);
  EXPECT_NEAR(left.lateral_offset(), 1.0, 0.02) << left.ShortDebugString();
  EXPECT_NEAR(left.distance(), 1.0, 0.02);
  EXPECT_NEAR(left.nearest().heading_deg(), heading, 1.0);
  ASSERT_EQ(left.ahead_size(), 4);
  proto::Vec3 previous = Vec(left.nearest().position().x(), left.nearest().position().y(), 0);
  for (const auto& point : left.ahead()) {
    const proto::Vec3 here = Vec(point.position().x(), point.position().y(), 0);
    EXPECT_NEAR(PlaneDistance(here, previous), 2.0, 0.05) << left.ShortDebugString();
    previous = here;
  }
  // Facing the other way, the same point belongs to the opposite lane (4 m
  // left of ours), 3 m to that lane's left.
  const proto::RoadQueryResult opposite = client_->QueryRoad(x, y, 0, 0, heading + 180);
  EXPECT_NEAR(opposite.lateral_offset(), 3.0, 0.05) << opposite.ShortDebugString();
}

// Fields the network thread checks: refused at once, with the request_id
// echoed and the field named; the connection stays usable.
TEST_F(MapTest, BadConfigureFieldsAreRefusedNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  struct Case {
    const char* field;
    std::function<void(proto::Configure&)> fill;
  };
  const Case cases[] = {
      {"carries no request", [](proto::Configure&) {}},
      {"Spawn.position.x is nan",
       [&](proto::Configure& c) {
         c.mutable_spawn()->set_kind(proto::ENTITY_KIND_UAV);
         *c.mutable_spawn()->mutable_position() = Vec(nan, 0, 20);
       }},
      {"CommandUav.hold.position.y is nan",
       [&](proto::Configure& c) { *c.mutable_command_uav()->mutable_hold()->mutable_position() = Vec(0, nan, 10); }},
      {"AddCamera.width is 8",
       [](proto::Configure& c) {
         c.mutable_add_camera()->set_name("c");
         c.mutable_add_camera()->set_width(8);
       }},
      {"AddCamera.height is 5000",
       [](proto::Configure& c) {
         c.mutable_add_camera()->set_name("c");
         c.mutable_add_camera()->set_width(64);
         c.mutable_add_camera()->set_height(5000);
       }},
      {"SetRoute.speed is 50",
       [](proto::Configure& c) {
         c.mutable_set_route()->set_keep_route(true);
         c.mutable_set_route()->set_speed(50);
       }},
      {"QueryRoad.count is 101", [](proto::Configure& c) { c.mutable_query_road()->set_count(101); }},
  };
  uint32_t request_id = 100;
  for (const Case& test : cases) {
    proto::Envelope envelope;
    envelope.mutable_configure()->set_request_id(++request_id);
    test.fill(*envelope.mutable_configure());
    client_->SendEnvelope(envelope);
    const proto::Error error = NextError(*client_, proto::ERROR_CODE_INVALID_ARGUMENT);
    EXPECT_EQ(error.request_id(), request_id) << error.message();
    EXPECT_NE(error.message().find(test.field), std::string::npos) << "'" << test.field << "' not in: " << error.message();
  }
  // Through the client library, with its own request ids.
  ExpectRefused([&] { client_->UavVelocity(2, 25, 0, 0); }, proto::ERROR_CODE_INVALID_ARGUMENT,
                {"CommandUav.velocity.velocity.x is 25"});
  const proto::WorldInfo world = client_->GetWorld();
  EXPECT_EQ(world.entities_size(), 2) << "nothing was changed";
  EXPECT_EQ(world.cameras_size(), 3);
}

}  // namespace
}  // namespace sim4cv::testing
