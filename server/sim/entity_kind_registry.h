// Kinds of entity beyond entity_kinds.h's table, registered at run time: a
// kind in a file of its own (its behaviour and its table row) plus one
// RegisterEntityKind line, with no edit to the World, the renderer or the
// protocol's checks. Such a kind is kinematic (it has no Bullet body: its
// behaviour moves it each physics step, as pedestrians are moved) and is
// drawn as a box of its colour. docs/architecture.md, "Extending sim4cv".
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <deque>
#include <string_view>

#include "server/sim/entity_kinds.h"
#include "server/sim/state.h"

namespace sim4cv::sim {

class KindBehaviour {
 public:
  virtual ~KindBehaviour() = default;
  // A new entity of the kind at `position` facing `yaw` (rad): fills its
  // body (World::Spawn has checked the pose is finite). Throws
  // std::invalid_argument naming what it cannot take.
  virtual void Spawn(const Eigen::Vector3d& position, double yaw, Entity& entity) const = 0;
  // One physics step of `dt` seconds: moves `entity` (its body; `state` is
  // the world as the step began, read-only). Deterministic, no allocation.
  virtual void Step(Entity& entity, const State& state, double dt) const = 0;
};

struct EntityKindEntry {
  EntityKindInfo info;            // its EntityKind value (Spawn.kind on the wire), name, run-log class
  uint32_t object_class;          // the protocol's ObjectClass of its boxes and 3D ground truth
  Eigen::Vector3d half_extents;   // its 3D box, about the body's position, in its own axes (m)
  std::array<float, 3> colour;    // the box the renderer draws, linear RGB
  const KindBehaviour* behaviour;  // outlives every World
};

// Before the daemon starts (not thread-safe against lookups). Throws
// std::invalid_argument if the value or the name is taken.
void RegisterEntityKind(const EntityKindEntry& entry);
// The registered kind of that value, or nullptr (entity_kinds.h's own kinds are not registered).
const EntityKindEntry* FindRegisteredKind(EntityKind kind);
// Every registered kind, in the order of registration.
const std::deque<EntityKindEntry>& RegisteredKinds();

}  // namespace sim4cv::sim
