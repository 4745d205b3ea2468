#include "app/fit_inputs.h"

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "acquisition/output_file.h"
#include "acquisition/recording_csv.h"
#include "analysis/parameter_file.h"
#include "analysis/preprocessing.h"
#include "app/commands.h"

namespace doorbench::app {

bool is_hdf5_file(const std::string& path) {
  // Every HDF5 file starts with this signature (at offset 0 for files HDF5 itself made).
  static constexpr char kSignature[8] = {'\x89', 'H', 'D', 'F', '\r', '\n', '\x1a', '\n'};
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open for reading");
  char head[8] = {};
  in.read(head, sizeof head);
  return in.gcount() == 8 && std::equal(head, head + 8, kSignature);
}

PreparedData load_prepared_data(const std::string& path) {
  if (is_hdf5_file(path)) return prepare_session(path);
  if (path.ends_with(".h5") || path.ends_with(".hdf5")) {
    throw std::runtime_error(path + ": not an HDF5 file (a session starts with the HDF5 "
                                    "signature; a CSV recording is read only under another name)");
  }
  return prepare(read_recording_csv(path, EmptyCells::kMissing));  // empty cells: lost samples
}

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> names;
  std::size_t start = 0;
  while (start < list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    if (comma > start) names.push_back(list.substr(start, comma - start));
    start = comma + 1;
  }
  return names;
}

std::vector<EffectSetting> effects_from_argument(const std::string& argument) {
  if (argument.empty()) return {};
  if (argument.size() > 5 && argument.ends_with(".json")) {
    return parse_effects_file(read_text_file(argument), argument);
  }
  std::vector<EffectSetting> settings;
  std::size_t start = 0;
  while (start <= argument.size()) {
    const std::size_t comma = std::min(argument.find(',', start), argument.size());
    const std::string name = argument.substr(start, comma - start);
    const std::optional<effects::Kind> kind = effects::find(name);
    if (!kind) {
      std::string known;
      for (const effects::EffectInfo& info : effects::catalogue()) {
        known += (known.empty() ? "" : ", ") + std::string(info.name);
      }
      throw UsageError("--effects: unknown effect '" + name + "' (the catalogue has " + known +
                       "; or give an effects file *.json)");
    }
    EffectSetting setting{*kind, {}, {}};
    for (const effects::EffectParameter& parameter : effects::info(*kind).parameters) {
      setting.values.push_back(parameter.default_value);
      setting.bounds.push_back(parameter.default_bounds);
    }
    settings.push_back(std::move(setting));
    start = comma + 1;
  }
  return settings;
}

DoorModel start_model(const std::string& model_kind, const std::string& params_path,
                      const std::string& effects_argument) {
  const std::optional<ModelKind> kind = parse_model_kind(model_kind);
  if (!kind) throw UsageError("--model must be sensory or physical, not " + model_kind);
  const DoorModel base = load_model(*kind, params_path, "");
  DoorModel model = base;
  for (EffectSetting& effect : effects_from_argument(effects_argument)) {
    model = model.with_effect(std::move(effect));
  }
  return model;
}

void add_fit_data_options(CLI::App& command, FitDataOptions& options,
                          const std::string& effects_help) {
  command.add_option("DATA", options.data_path, "Session (HDF5) or recording (CSV)")->required();
  command.add_option("--model", options.model.model, "Which door model")
      ->check(CLI::IsMember({"sensory", "physical"}))
      ->capture_default_str();
  command.add_option("--params", options.model.params_path,
                     "Start values and bounds (parameter file); default: the reference door");
  command.add_option("--effects", options.model.effects_path, effects_help);
  command.add_flag("--overwrite", options.overwrite,
                   "Write into an --out folder that exists and is not empty (files of the same "
                   "names are replaced)");
}

std::vector<std::filesystem::path> fit_input_paths(const FitDataOptions& options) {
  std::vector<std::filesystem::path> inputs{options.data_path};
  if (!options.model.params_path.empty()) inputs.emplace_back(options.model.params_path);
  if (options.model.effects_path.ends_with(".json")) inputs.emplace_back(options.model.effects_path);
  return inputs;
}

FitInputs prepare_fit_run(const FitDataOptions& options, const std::filesystem::path& out_dir) {
  check_output_folder(out_dir, fit_input_paths(options), options.overwrite);
  FitInputs inputs = load_fit_inputs(options);
  std::filesystem::create_directories(out_dir);
  return inputs;
}

FitInputs load_fit_inputs(const FitDataOptions& options) {
  std::cerr << "preparing " << options.data_path << "\n";
  PreparedData data = load_prepared_data(options.data_path);
  std::cerr << "  " << data.strokes.size() << " strokes, " << data.excluded.size()
            << " segments excluded\n";
  for (const std::string& warning : data.warnings) std::cerr << "warning: " << warning << "\n";
  for (const ExcludedSegment& e : data.excluded) {
    if (!e.lost_samples) continue;  // gaps are never silent
    char span[64];
    std::snprintf(span, sizeof span, "%.3f s to %.3f s", e.start_s, e.end_s);
    std::cerr << "  excluded " << span << ": " << e.reason << "\n";
  }
  DoorModel start =
      start_model(options.model.model, options.model.params_path, options.model.effects_path);
  if (!data.geometry_calibration_id.empty() && data.handle_radius_m > 0) {
    // The bench's calibrated geometry, not the door file's nominal radius.
    DoorGeometry geometry = start.geometry();
    std::cerr << "  the door file's handle radius " << geometry.handle_radius_m
              << " m is replaced\n";
    geometry.handle_radius_m = data.handle_radius_m;
    const std::span<const double> values = start.parameter_values();
    const std::span<const Bounds> bounds = start.parameter_bounds();
    const auto base = static_cast<std::size_t>(start.base_parameter_count());
    start = DoorModel(start.kind(), geometry, {values.begin(), values.begin() + base},
                      {bounds.begin(), bounds.begin() + base},
                      {start.effects().begin(), start.effects().end()});
  }
  std::cerr << "  " << handle_radius_line(data, start) << "\n";
  return {std::move(data), std::move(start)};
}

std::string handle_radius_line(const PreparedData& data, const DoorModel& model) {
  std::ostringstream line;
  line << "handle radius " << model.geometry().handle_radius_m << " m, from ";
  if (!data.geometry_calibration_id.empty() && data.handle_radius_m > 0) {
    line << "geometry record " << data.geometry_calibration_id
         << " (the force corrected for the load cell's mounting angle)";
  } else {
    line << "the door parameter file";
  }
  return line.str();
}

}  // namespace doorbench::app
