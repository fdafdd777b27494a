#include "server/daemon/state_message.h"

#include "server/wire/proto_math.h"

namespace sim4cv::daemon {

using wire::SetQuaternion;
using wire::SetVec3;

void FillStateMessage(const sim::State& state, proto::State& out) {
  out.set_frame_id(state.frame_id);
  out.set_sim_time(state.sim_time);
  // Clear() keeps the repeated elements' memory, so the hot path reuses them.
  out.mutable_entities()->Clear();
  for (const sim::Entity& entity : state.entities) {
    proto::EntityState& message = *out.add_entities();
    message.set_id(entity.id);
    message.set_name(entity.name);
    message.set_kind(static_cast<proto::EntityKind>(entity.kind));
    SetVec3(entity.body.position, *message.mutable_position());
    SetQuaternion(entity.body.orientation, *message.mutable_orientation());
    SetVec3(entity.body.linear_velocity, *message.mutable_linear_velocity());
    SetVec3(entity.body.angular_velocity, *message.mutable_angular_velocity());
  }
}

}  // namespace sim4cv::daemon
