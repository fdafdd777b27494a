#include "server/daemon/state_message.h"

#include "server/session/proto_math.h"

namespace sim4cv::daemon {
namespace {

using session::SetQuaternion;
using session::SetVec3;

void FillEntity(uint32_t id, const std::string& name, proto::EntityKind kind, const sim::BodyState& body,
                proto::EntityState& out) {
  out.set_id(id);
  out.set_name(name);
  out.set_kind(kind);
  SetVec3(body.position, *out.mutable_position());
  SetQuaternion(body.orientation, *out.mutable_orientation());
  SetVec3(body.linear_velocity, *out.mutable_linear_velocity());
  SetVec3(body.angular_velocity, *out.mutable_angular_velocity());
}

}  // namespace

void FillStateMessage(const sim::Scene& scene, const sim::State& state, proto::State& out) {
  out.set_frame_id(state.frame_id);
  out.set_sim_time(state.sim_time);
  // Clear() keeps the repeated elements' memory, so the hot path reuses them.
  out.mutable_entities()->Clear();
  FillEntity(sim::kCarEntityId, scene.car.name, proto::ENTITY_KIND_CAR, state.car, *out.add_entities());
  FillEntity(sim::kUavEntityId, scene.uav.name, proto::ENTITY_KIND_UAV, state.uav, *out.add_entities());
}

void FillEntityInfos(const sim::Scene& scene, proto::Welcome& welcome) {
  auto add = [&](uint32_t id, const std::string& name, proto::EntityKind kind) {
    proto::EntityInfo* info = welcome.add_entities();
    info->set_id(id);
    info->set_name(name);
    info->set_kind(kind);
  };
  add(sim::kCarEntityId, scene.car.name, proto::ENTITY_KIND_CAR);
  add(sim::kUavEntityId, scene.uav.name, proto::ENTITY_KIND_UAV);
}

}  // namespace sim4cv::daemon
