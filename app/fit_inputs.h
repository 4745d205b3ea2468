#pragma once
// What `doorbench fit` (and later `loop`) read: the data, prepared, and the start model.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/door_model.h"
#include "analysis/strokes.h"
#include "app/commands.h"

namespace doorbench::app {

// Whether `path` is an HDF5 file (a session), by its signature. Throws std::runtime_error
// when it cannot be opened.
bool is_hdf5_file(const std::string& path);

// A session (HDF5: by its signature) or a recording in the CSV exchange format, prepared
// into strokes (analysis/preprocessing.h); empty cells of the CSV are missing samples. A
// file named *.h5 or *.hdf5 that is not HDF5 is refused ("PATH: not an HDF5 file ...").
PreparedData load_prepared_data(const std::string& path);

// "a,b,,c" -> {"a", "b", "c"}: the parameter lists of --free and --fixed (empty items dropped).
std::vector<std::string> split_names(const std::string& list);

// --effects takes an effects file (*.json) or a comma-separated list of catalogue names,
// each switched on at its catalogue default values and bounds.
std::vector<EffectSetting> effects_from_argument(const std::string& argument);

// The start model: the parameter file (or the reference door) plus the effects.
DoorModel start_model(const std::string& model_kind, const std::string& params_path,
                      const std::string& effects_argument);

// The options `fit` and `loop` share: DATA, --model, --params, --effects, --overwrite.
struct FitDataOptions {
  std::string data_path;
  ModelOptions model;
  bool overwrite = false;  // write into an --out folder that is not empty
};
// DATA, --params and an --effects file: what the --out folder must not hold.
std::vector<std::filesystem::path> fit_input_paths(const FitDataOptions& options);
// The output rule for the --out folder (acquisition/output_file.h), then the inputs are
// read (load_fit_inputs), and only then is the folder created: a failure leaves no folder.
// Returns the inputs.
void add_fit_data_options(CLI::App& command, FitDataOptions& options,
                          const std::string& effects_help);

struct FitInputs {
  PreparedData data;
  DoorModel start;
};
// Prepares DATA and builds the start model, reporting progress on stderr. When the data
// carries a geometry record (a session's load cell with geometry_calibration_id), the
// record's handle radius replaces the door file's in the start model.
FitInputs load_fit_inputs(const FitDataOptions& options);
FitInputs prepare_fit_run(const FitDataOptions& options, const std::filesystem::path& out_dir);

// Which handle radius `model` has and where it came from, one line for reports: "handle
// radius 0.62 m, from geometry record geometry-B1-v2" or "…, from the door parameter file".
std::string handle_radius_line(const PreparedData& data, const DoorModel& model);

}  // namespace doorbench::app
