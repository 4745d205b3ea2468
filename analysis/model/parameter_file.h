#pragma once
// Parameter files in the layout of reference-door.json: top-level handle_radius_m and
// theta_max_rad, a "sensory" and/or "physical" section of {"value", "bounds"} entries.
// Effects files name the effects to switch on:
//   { "stribeck": { "d_s": {"value": 3.2, "bounds": [0, 20]}, "w_s": 0.05 } }
// (a bare number takes the catalogue's bounds). Unknown or missing keys are rejected
// by name; every error is a ParameterFileError whose text starts with the file name.
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/model/door_model.h"

namespace doorbench {

class ParameterFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ModelSection {
  std::vector<double> values;
  std::vector<Bounds> bounds;
};

struct ParameterFile {
  DoorGeometry geometry;
  std::optional<ModelSection> sensory;
  std::optional<ModelSection> physical;
};

// `source` names the text in messages (a path, or "reference door").
ParameterFile parse_parameter_file(std::string_view json_text, std::string_view source);
std::vector<EffectSetting> parse_effects_file(std::string_view json_text, std::string_view source);

// The reference door shipped inside doorbench (analysis/data/reference-door.json).
std::string_view reference_door_json();
DoorModel reference_model(ModelKind kind);

// Builds a model from a parameter file (or the reference door when `params_path` is
// empty) and an optional effects file.
DoorModel load_model(ModelKind kind, const std::filesystem::path& params_path,
                     const std::filesystem::path& effects_path);

// A parameter file holding this model's base section and geometry, and the effects file
// of its effects (empty object when it has none).
std::string to_parameter_json(const DoorModel& model);
std::string to_effects_json(const DoorModel& model);

// Reads a whole text file; throws ParameterFileError naming the path when it cannot.
std::string read_text_file(const std::filesystem::path& path);

}  // namespace doorbench
