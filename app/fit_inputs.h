#pragma once
// What `doorbench fit` (and later `loop`) read: the data, prepared, and the start model.
#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/model/door_model.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/preprocessing/recording_file.h"
#include "analysis/preprocessing/strokes.h"
#include "app/commands.h"

namespace doorbench::app {

// PreparedData::handle_radius_origin: "" when the data states no radius.
std::string handle_radius_origin(const PreparedData& data);

// check_handle_radius throws UsageError naming the data's handle radius and where it came
// from when it is not where a door handle can be (handle_radius_problem,
// acquisition/session/recording_csv.h), unless `force_geometry`.
void check_handle_radius(const PreparedData& data, bool force_geometry);

// "a,b,,c" -> {"a", "b", "c"}: the parameter lists of --free and --fixed (empty items dropped).
std::vector<std::string> split_names(const std::string& list);

// Each of `names` (given to `option`, e.g. "--free") must be a parameter of `model`; else
// UsageError (exit 2) naming the option, the name and the model's parameters: "--free: the
// sensory model has no parameter 'bogus' (its parameters: J, k, ...)". For the names of
// fit --free/--fixed and spec --fixed/--costs, checked before any data is read.
void check_parameter_names(const DoorModel& model, const std::string& option,
                           const std::vector<std::string>& names);

// --effects takes an effects file (*.json) or a comma-separated list of catalogue names,
// each switched on at its catalogue default values and bounds.
std::vector<EffectSetting> effects_from_argument(const std::string& argument);

// The start model: the parameter file (or the reference door) plus the effects.
DoorModel start_model(const std::string& model_kind, const std::string& params_path,
                      const std::string& effects_argument);

// The options `fit` and `loop` share: DATA, --model, --params, --effects, the filters
// (--derivative-cutoff-hz, --force-cutoff-hz, --min-sample-rate-hz), --strict-geometry,
// --start and --overwrite.
struct FitDataOptions {
  std::string data_path;
  ModelOptions model;
  PreprocessingOptions preprocessing;
  // A handle radius stated by the recording that differs from the parameter file's is an
  // error (default: a warning, and the recording's is used).
  bool strict_geometry = false;
  bool force_geometry = false;  // a handle radius outside 0.05 to 2 m is used, not refused
  // Where the start values come from (--start): "auto" (from the data without --params,
  // else the file's), "data" (from the data, the file or the reference door filling in what
  // the data do not give: analysis/fit/fit_init.h), "file" (the file's, or the reference door's).
  // From the data for the sensory model only.
  std::string start = "auto";
  bool overwrite = false;  // write into an --out folder that is not empty
};
// DATA, --params and an --effects file: what the --out folder must not hold.
std::vector<std::filesystem::path> fit_input_paths(const FitDataOptions& options);

// Every segment left out of the fit, named with its reason: preprocessing's exclusions
// (PreparedData::excluded) and the window fit's windows that span a recording gap (with the
// default window options of `start`: gap_window_exclusions), which are added to
// data.excluded (so that result.json lists them), in time order. Prints "N strokes, M
// segments excluded", the rate summary, the warnings and the first kExcludedListed
// exclusions ("excluded T1 s to T2 s: REASON") on stderr, and appends one report line
// listing them all.
inline constexpr std::size_t kExcludedListed = 20;
void list_excluded(PreparedData& data, const DoorModel& start,
                   std::vector<std::string>& report_lines);

void add_fit_data_options(CLI::App& command, FitDataOptions& options,
                          const std::string& effects_help);

struct FitInputs {
  PreparedData data;
  DoorModel start;
  // Lines for the report (warnings first, then where the start values came from).
  std::vector<std::string> report_lines;
  // Per base parameter of `start`: where its start value came from.
  std::vector<std::string> start_origin;
};
// Prepares DATA and builds the start model, reporting progress on stderr. The recording's
// geometry wins: when the data states a handle radius (a session's geometry record, its
// handle_radius_m, or a CSV's `# handle_radius_m:`), it replaces the parameter file's (or
// the reference door's) in the start model. A difference from a parameter file given with
// --params is a warning on stderr and in report_lines; with strict_geometry it throws
// std::runtime_error naming both radii and where they came from.
FitInputs load_fit_inputs(const FitDataOptions& options);
// The output rule for the --out folder (acquisition/session/output_file.h), then the inputs are
// read (load_fit_inputs), and only then is the folder created: a failure leaves no folder.
// Returns the inputs.
FitInputs prepare_fit_run(const FitDataOptions& options, const std::filesystem::path& out_dir);

// Which handle radius `model` has and where it came from, one line for reports: "handle
// radius 0.62 m, from geometry record geometry-B1-v2 (...)", "…, from the CSV's metadata
// (# handle_radius_m)" or "…, from the door parameter file" (the data states none).
std::string handle_radius_line(const PreparedData& data, const DoorModel& model);

}  // namespace doorbench::app
