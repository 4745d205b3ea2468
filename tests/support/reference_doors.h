#pragma once
// The reference doors as the analysis tests start from them (analysis/model/parameter_file.h's
// reference_model), by value, for tests that change them, and with the effects
// several tests add. Header-only, test code.
#include <utility>

#include "analysis/model/effects.h"
#include "analysis/model/parameter_file.h"

namespace doorbench::testing {

inline DoorModel sensory_reference() {
  return reference_model(ModelKind::kSensory);
}

// The sensory reference's friction coefficient d1, N·m.
inline double sensory_reference_d1() {
  const DoorModel model = sensory_reference();
  return model.parameter_values()[*model.find_parameter("d1")];
}

// `model` with breakaway (Stribeck) friction added: d_s_N_m, w_s = speed_rad_s, within the
// catalogue's bounds.
inline DoorModel with_breakaway(const DoorModel& model, double d_s_N_m, double speed_rad_s) {
  EffectSetting setting{effects::Kind::kStribeck, {d_s_N_m, speed_rad_s}, {}};
  for (const effects::EffectParameter& parameter :
       effects::info(effects::Kind::kStribeck).parameters) {
    setting.bounds.push_back(parameter.default_bounds);
  }
  return model.with_effect(std::move(setting));
}

// The sensory reference with breakaway friction: d_s = d1 + excess_N_m, w_s = speed_rad_s.
inline DoorModel sensory_reference_with_breakaway(double excess_N_m, double speed_rad_s) {
  return with_breakaway(sensory_reference(), sensory_reference_d1() + excess_N_m, speed_rad_s);
}

}  // namespace doorbench::testing
