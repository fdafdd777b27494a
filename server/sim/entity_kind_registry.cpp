#include "server/sim/entity_kind_registry.h"

#include <stdexcept>
#include <string>

namespace sim4cv::sim {
namespace {

std::deque<EntityKindEntry>& Registered() {  // a deque: entries stay where they are as it grows
  static std::deque<EntityKindEntry> registered;
  return registered;
}

}  // namespace

const std::deque<EntityKindEntry>& RegisteredKinds() { return Registered(); }

void RegisterEntityKind(const EntityKindEntry& entry) {
  for (const EntityKindInfo& taken : kEntityKinds) {
    if (taken.kind == entry.info.kind || taken.name == entry.info.name) {
      throw std::invalid_argument("entity kind '" + std::string(entry.info.name) + "' (" +
                                  std::to_string(static_cast<int>(entry.info.kind)) + ") clashes with '" +
                                  std::string(taken.name) + "'");
    }
  }
  for (const EntityKindEntry& taken : Registered()) {
    if (taken.info.kind == entry.info.kind || taken.info.name == entry.info.name) {
      throw std::invalid_argument("entity kind '" + std::string(entry.info.name) + "' is registered already");
    }
  }
  if (entry.behaviour == nullptr) throw std::invalid_argument("entity kind '" + std::string(entry.info.name) + "' has no behaviour");
  Registered().push_back(entry);
}

const EntityKindEntry* FindRegisteredKind(EntityKind kind) {
  for (const EntityKindEntry& entry : Registered()) {
    if (entry.info.kind == kind) return &entry;
  }
  return nullptr;
}

const EntityKindInfo* FindRegisteredEntityKind(int value) {
  const EntityKindEntry* entry = value >= 0 && value < 256 ? FindRegisteredKind(static_cast<EntityKind>(value)) : nullptr;
  return entry ? &entry->info : nullptr;
}

}  // namespace sim4cv::sim
