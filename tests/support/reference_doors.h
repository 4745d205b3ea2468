#pragma once
// The reference doors as the analysis tests start from them (analysis/model/parameter_file.h's
// reference_model), by value, for tests that change them. Header-only, test code.
#include "analysis/model/parameter_file.h"

namespace doorbench::testing {

inline DoorModel sensory_reference() { return reference_model(ModelKind::kSensory); }

}  // namespace doorbench::testing
