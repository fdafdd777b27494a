// The kinds of entity (a thing that moves in the world: the target car, a
// UAV, a pedestrian), listed once. The protocol's EntityKind and ObjectClass
// (server/wire/entity_kinds_wire.h asserts they agree), the World's names
// for them, the run log's object classes and the Configure checks all read
// this table; adding a kind is one line here plus its behaviour (its vehicle
// in World, its mesh in SceneGraphics), or, for a kinematic kind drawn as a
// box, one file registered at run time (entity_kind_registry.h).
#pragma once

#include <array>
#include <cstdint>
#include <string_view>
#include <type_traits>


namespace sim4cv::sim {

// X(Name, value: proto EntityKind, WIRE: the proto enums' suffix, "name",
//   run-log object class (runlog::kObjectClass*; daemon/run_logger.cpp asserts they agree))
#define SIM4CV_ENTITY_KINDS(X)                     \
  X(Car, 1, CAR, "car", 1)                        \
  X(Uav, 2, UAV, "UAV", 2)                        \
  X(Pedestrian, 3, PEDESTRIAN, "pedestrian", 7)

enum class EntityKind : uint8_t {
#define SIM4CV_ENTITY_KIND_ENUM(NAME, VALUE, ...) k##NAME = VALUE,
  SIM4CV_ENTITY_KINDS(SIM4CV_ENTITY_KIND_ENUM)
#undef SIM4CV_ENTITY_KIND_ENUM
};

struct EntityKindInfo {
  EntityKind kind;
  std::string_view name;   // in messages and logs
  uint16_t log_class;      // its object class in run logs (docs/logs.md)
};

inline constexpr std::array kEntityKinds = {
#define SIM4CV_ENTITY_KIND_INFO(NAME, VALUE, WIRE, TEXT, LOG_CLASS) EntityKindInfo{EntityKind::k##NAME, TEXT, LOG_CLASS},
    SIM4CV_ENTITY_KINDS(SIM4CV_ENTITY_KIND_INFO)
#undef SIM4CV_ENTITY_KIND_INFO
};

// A kind registered at run time (entity_kind_registry.h), or nullptr.
const EntityKindInfo* FindRegisteredEntityKind(int value);

// The kind whose protocol value is `value`, or nullptr: the table's, then
// (at run time) the registered ones.
constexpr const EntityKindInfo* FindEntityKind(int value) {
  for (const EntityKindInfo& info : kEntityKinds) {
    if (static_cast<int>(info.kind) == value) return &info;
  }
  if (std::is_constant_evaluated()) return nullptr;
  return FindRegisteredEntityKind(value);
}

constexpr const EntityKindInfo& InfoOf(EntityKind kind) { return *FindEntityKind(static_cast<int>(kind)); }

}  // namespace sim4cv::sim
