#pragma once
// What `doorbench fit` (and later `loop`) read: the data, prepared, and the start model.
#include <string>

#include "analysis/door_model.h"
#include "analysis/strokes.h"

namespace doorbench::app {

// A session (HDF5: by its signature) or a recording in the CSV exchange format, prepared
// into strokes (analysis/preprocessing.h).
PreparedData load_prepared_data(const std::string& path);

// --effects takes an effects file (*.json) or a comma-separated list of catalogue names,
// each switched on at its catalogue default values and bounds.
std::vector<EffectSetting> effects_from_argument(const std::string& argument);

// The start model: the parameter file (or the reference door) plus the effects.
DoorModel start_model(const std::string& model_kind, const std::string& params_path,
                      const std::string& effects_argument);

}  // namespace doorbench::app
