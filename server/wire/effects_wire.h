// The camera effects (protocol/effects.h) on the wire: proto CameraEffects
// has one field per entry of the table, of the same name, so these read and
// write it by that name (protobuf reflection) instead of listing the fields
// again; effects_wire_test checks every entry has its field.
#pragma once

#include <string>

#include "protocol/effects.h"
#include "server/common/check.h"
#include "sim4cv.pb.h"

namespace sim4cv::wire {

// Sets the effects the message carries (fields present); the rest stay.
inline void ApplyEffects(const proto::CameraEffects& message, effects::CameraEffects& out) {
  const auto* reflection = message.GetReflection();
  for (const effects::EffectInfo& info : effects::kEffects) {
    const auto* field = message.GetDescriptor()->FindFieldByName(std::string(info.field));
    SIM4CV_DEMAND(field != nullptr);
    if (reflection->HasField(message, field)) out.*info.member = reflection->GetDouble(message, field);
  }
}

// Every field of `out` from `effects`.
inline void FillEffects(const effects::CameraEffects& effects, proto::CameraEffects& out) {
  const auto* reflection = out.GetReflection();
  for (const effects::EffectInfo& info : effects::kEffects) {
    const auto* field = out.GetDescriptor()->FindFieldByName(std::string(info.field));
    SIM4CV_DEMAND(field != nullptr);
    reflection->SetDouble(&out, field, effects.*info.member);
  }
}

}  // namespace sim4cv::wire
