// The entity kinds (server/sim/entity_kinds.h) on the wire: their protocol
// EntityKind must be their value (checked here at compile time, kind by
// kind), their ObjectClass, and the list a refused Spawn names.
#pragma once

#include <string>
#include <type_traits>
#include <vector>

#include "server/sim/entity_kind_registry.h"
#include "server/sim/entity_kinds.h"
#include "sim4cv.pb.h"

namespace sim4cv::wire {

#define SIM4CV_ENTITY_KIND_WIRE_CHECK(NAME, VALUE, WIRE, ...)                                             \
  static_assert(static_cast<int>(sim::EntityKind::k##NAME) == proto::ENTITY_KIND_##WIRE,                  \
                "sim::EntityKind::k" #NAME " must equal proto::ENTITY_KIND_" #WIRE);                     \
  static_assert(proto::OBJECT_CLASS_##WIRE > 0, "every entity kind has an ObjectClass");
SIM4CV_ENTITY_KINDS(SIM4CV_ENTITY_KIND_WIRE_CHECK)
#undef SIM4CV_ENTITY_KIND_WIRE_CHECK

// The ObjectClass of an entity of `kind` in boxes and 3D ground truth.
constexpr proto::ObjectClass ObjectClassOf(sim::EntityKind kind) {
  switch (kind) {
#define SIM4CV_ENTITY_KIND_CLASS(NAME, VALUE, WIRE, ...) \
  case sim::EntityKind::k##NAME:                         \
    return proto::OBJECT_CLASS_##WIRE;
    SIM4CV_ENTITY_KINDS(SIM4CV_ENTITY_KIND_CLASS)
#undef SIM4CV_ENTITY_KIND_CLASS
  }
  if (std::is_constant_evaluated()) return proto::OBJECT_CLASS_UNSPECIFIED;
  const sim::EntityKindEntry* registered = sim::FindRegisteredKind(kind);
  return registered ? static_cast<proto::ObjectClass>(registered->object_class) : proto::OBJECT_CLASS_UNSPECIFIED;
}

// "ENTITY_KIND_CAR (1), ENTITY_KIND_UAV (2) or ENTITY_KIND_PEDESTRIAN (3)",
// then the registered kinds by name ("beacon (9)").
inline std::string EntityKindChoices() {
  std::vector<std::string> choices;
  for (const sim::EntityKindInfo& info : sim::kEntityKinds) {
    const int value = static_cast<int>(info.kind);
    choices.push_back(proto::EntityKind_Name(static_cast<proto::EntityKind>(value)) + " (" + std::to_string(value) + ")");
  }
  for (const sim::EntityKindEntry& entry : sim::RegisteredKinds()) {
    choices.push_back(std::string(entry.info.name) + " (" + std::to_string(static_cast<int>(entry.info.kind)) + ")");
  }
  std::string text;
  for (std::size_t i = 0; i < choices.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
  }
  return text;
}

}  // namespace sim4cv::wire
