#include "fuzz/protocol_harness.h"

#include "fuzz/fuzz_input.h"
#include "protocol/framing.h"
#include "server/common/limits.h"

namespace sim4cv::fuzz {
namespace {

proto::Welcome MakeWelcome(proto::SimMode mode) {
  proto::Welcome welcome;
  welcome.set_protocol_version(wire::kProtocolVersion);
  welcome.set_server_version("fuzz");
  welcome.set_mode(mode);
  welcome.set_physics_hz(240);
  welcome.set_frame_hz(30);
  return welcome;
}

}  // namespace

ProtocolHarness::ProtocolHarness(proto::SimMode mode)
    : context_{scene_,   mode, MakeWelcome(mode), world_, commands_, latest_state_, limits::kDefaultMaxMessageBytes,
               counters_,
               "",
               ""} {
  // What the sim thread publishes for the default scene: its entities and cameras.
  proto::WorldInfo world;
  world.set_scene_name("default");
  for (const char* name : {"uav", "chase", "uav_down"}) {
    proto::CameraInfo* camera = world.add_cameras();
    camera->set_name(name);
    camera->set_width(320);
    camera->set_height(180);
  }
  world.add_cameras();  // a removed camera: nameless, its index kept
  world_.Publish(world);
}

void ProtocolHarness::DrainCommands() {
  commands_.Drain(drained_);
  drained_.clear();
}

FuzzSession::FuzzSession(const session::ServerContext& context)
    : protocol(session::NewClientId(), context, link, &mailbox) {}

FuzzSession::~FuzzSession() { protocol.Disconnect(); }

ProtocolHarness& SharedHarness() {
  static auto* harness = [] {
    QuietLogs();
    return new ProtocolHarness(proto::SIM_MODE_LOCKSTEP);
  }();
  return *harness;
}

}  // namespace sim4cv::fuzz
