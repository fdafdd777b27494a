// An entity kind added as one file plus one registration line
// (beacon_kind.cpp): the daemon's own RunDaemon, in this process, spawns
// it through Configure, steps it, draws it into the mask and labels its box,
// and refuses what the kind refuses, over TCP as for every kind.
#include <gtest/gtest.h>

#include <cmath>

#include "server/sim/entity_kind_registry.h"
#include "tests/extending/in_process_daemon.h"
#include "tests/integration/raw_connection.h"

namespace sim4cv::demo {
extern const sim::EntityKindEntry kBeacon;
}

namespace sim4cv {
namespace {

using namespace std::chrono_literals;

proto::Envelope Exchange(testing::RawConnection& connection, const proto::Envelope& request) {
  EXPECT_TRUE(connection.Send(testing::Framed(request)));
  const auto reply = connection.Receive(120s);
  EXPECT_TRUE(reply.has_value()) << "no answer to " << request.ShortDebugString();
  return reply.value_or(proto::Envelope());
}

proto::Envelope SpawnBeacon(uint32_t request_id, double x, double y, double z, int kind = 9) {
  proto::Envelope request;
  proto::Configure& configure = *request.mutable_configure();
  configure.set_request_id(request_id);
  configure.mutable_spawn()->set_kind(static_cast<proto::EntityKind>(kind));  // no ENTITY_KIND_ name: a number
  configure.mutable_spawn()->mutable_position()->set_x(x);
  configure.mutable_spawn()->mutable_position()->set_y(y);
  configure.mutable_spawn()->mutable_position()->set_z(z);
  return request;
}

double YawOf(const proto::State& state, uint32_t id) {
  for (const proto::EntityState& entity : state.entities()) {
    if (entity.id() != id) continue;
    const auto& q = entity.orientation();
    return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
  }
  ADD_FAILURE() << "no entity " << id << " in the State";
  return 0.0;
}

TEST(ExtendingEntityKind, ARegisteredKindIsSpawnedSteppedDrawnAndLabelled) {
  sim::RegisterEntityKind(demo::kBeacon);  // the one registration line

  testing::InProcessDaemon daemon({"--tcp-port", "0", "--udp-port", "-1", "--mode", "lockstep"});
  testing::RawConnection connection(daemon.tcp_port());
  ASSERT_TRUE(connection.Send(testing::FramedHello("beacon", testing::InProcessDaemon::kToken)));
  ASSERT_TRUE(connection.Receive(120s).value_or(proto::Envelope()).has_welcome());

  const proto::Envelope spawned = Exchange(connection, SpawnBeacon(1, 200.0, 200.0, 0.0));
  ASSERT_TRUE(spawned.has_configured()) << spawned.ShortDebugString();
  const uint32_t beacon = spawned.configured().entity_id();
  bool listed = false;
  for (const auto& entity : spawned.configured().world().entities()) {
    listed |= entity.id() == beacon && entity.name() == "beacon_" + std::to_string(beacon) && entity.kind() == 9;
  }
  EXPECT_TRUE(listed) << spawned.configured().world().ShortDebugString();

  // A world-fixed camera 6 m west of it, looking east at it.
  proto::Envelope camera;
  camera.mutable_configure()->set_request_id(2);
  proto::AddCamera& add = *camera.mutable_configure()->mutable_add_camera();
  add.set_name("beacon_view");
  add.set_width(64);
  add.set_height(48);
  add.set_fov_y_deg(60.0);
  add.mutable_offset()->set_x(194.0);
  add.mutable_offset()->set_y(200.0);
  add.mutable_offset()->set_z(1.0);
  ASSERT_TRUE(Exchange(connection, camera).has_configured());

  proto::Envelope subscribe;
  subscribe.mutable_subscribe()->set_camera("beacon_view");
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_MASK);
  subscribe.mutable_subscribe()->add_channels(proto::CHANNEL_BOXES);
  subscribe.mutable_subscribe()->set_delivery(proto::DELIVERY_LOCKSTEP);
  subscribe.mutable_subscribe()->set_with_state(true);
  ASSERT_TRUE(Exchange(connection, subscribe).has_subscribed());
  proto::Envelope step;
  step.mutable_step();
  const proto::Frame first = Exchange(connection, step).frame();
  const proto::Frame second = Exchange(connection, step).frame();
  ASSERT_GT(second.frame_id(), first.frame_id());

  // Drawn into the mask with its id, and boxed as the obstacle it is labelled.
  ASSERT_EQ(second.images_size(), 1);
  const auto* ids = reinterpret_cast<const uint16_t*>(second.images(0).data().data());
  int beacon_pixels = 0;
  for (uint32_t i = 0; i < second.width() * second.height(); ++i) beacon_pixels += ids[i] == beacon ? 1 : 0;
  EXPECT_GT(beacon_pixels, 20);
  bool boxed = false;
  for (const proto::Box& box : second.boxes()) {
    boxed |= box.object_id() == beacon && box.object_class() == proto::OBJECT_CLASS_OBSTACLE &&
             box.visible_pixels() == static_cast<uint32_t>(beacon_pixels);
  }
  EXPECT_TRUE(boxed) << second.ShortDebugString().substr(0, 600);
  // It turned at its rate between the two frames (its behaviour's Step, every physics step).
  const double turned = std::remainder(YawOf(second.state(), beacon) - YawOf(first.state(), beacon), 2.0 * M_PI);
  EXPECT_NEAR(turned, 0.5 * (second.sim_time() - first.sim_time()), 1e-6);

  // What the kind refuses is the requesting client's Error, and the Spawn refusal names it.
  const proto::Envelope in_the_air = Exchange(connection, SpawnBeacon(3, 210.0, 200.0, 3.0));
  ASSERT_TRUE(in_the_air.has_error());
  EXPECT_NE(in_the_air.error().message().find("a beacon stands on the ground"), std::string::npos)
      << in_the_air.error().message();
  const proto::Envelope unknown = Exchange(connection, SpawnBeacon(4, 210.0, 200.0, 0.0, 10));
  ASSERT_TRUE(unknown.has_error());
  EXPECT_NE(unknown.error().message().find("ENTITY_KIND_PEDESTRIAN (3) or beacon (9)"), std::string::npos)
      << unknown.error().message();

  connection.Close();
  EXPECT_EQ(daemon.Stop(), 0);
}

}  // namespace
}  // namespace sim4cv
