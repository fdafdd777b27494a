#include "server/daemon/state_message.h"

#include "server/session/proto_math.h"

namespace sim4cv::daemon {

using session::SetQuaternion;
using session::SetVec3;

void FillStateMessage(const sim::State& state, proto::State& out) {
  out.set_frame_id(state.frame_id);
  out.set_sim_time(state.sim_time);
  // Clear() keeps the repeated elements' memory, so the hot path reuses them.
  out.mutable_entities()->Clear();
  for (const sim::Agent& agent : state.agents) {
    proto::EntityState& entity = *out.add_entities();
    entity.set_id(agent.id);
    entity.set_name(agent.name);
    entity.set_kind(static_cast<proto::EntityKind>(agent.kind));
    SetVec3(agent.body.position, *entity.mutable_position());
    SetQuaternion(agent.body.orientation, *entity.mutable_orientation());
    SetVec3(agent.body.linear_velocity, *entity.mutable_linear_velocity());
    SetVec3(agent.body.angular_velocity, *entity.mutable_angular_velocity());
  }
}

}  // namespace sim4cv::daemon
