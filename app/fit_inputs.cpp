#include "app/fit_inputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"
#include "analysis/fit/fit_init.h"
#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/preprocessing.h"
#include "analysis/preprocessing/recording_file.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "core/number_format.h"

namespace doorbench::app {

std::string handle_radius_origin(const PreparedData& data) {
  return data.handle_radius_origin;
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

void check_parameter_names(const DoorModel& model, const std::string& option,
                           const std::vector<std::string>& names) {
  if (std::string problem = unknown_parameter_problem(model, option, names); !problem.empty()) {
    throw UsageError(problem);
  }
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
  command
      .add_option("--derivative-cutoff-hz", options.preprocessing.derivative_cutoff_hz,
                  "Low-pass before differentiating angle_rad (no gyroscope), Hz; 0: the rate's "
                  "rule min(30 Hz, sample rate / 4) (docs/preprocessing.md)")
      ->check(non_negative_number())
      ->capture_default_str();
  command
      .add_option("--force-cutoff-hz", options.preprocessing.force_cutoff_hz,
                  "Zero-phase low-pass on the force, Hz; 0: none")
      ->check(non_negative_number())
      ->capture_default_str();
  command
      .add_option("--min-sample-rate-hz", options.preprocessing.min_sample_rate_hz,
                  "Refuse recordings sampled more slowly than this")
      ->check(positive_number())
      ->capture_default_str();
  command
      .add_option("--start", options.start,
                  "Start values: auto (from the data without --params, else the file), data "
                  "(from the data; the file or the reference door fills in), file")
      ->check(CLI::IsMember({"auto", "data", "file"}))
      ->capture_default_str();
  command.add_flag("--strict-geometry", options.strict_geometry,
                   "A handle radius stated by the recording that differs from the --params "
                   "file's is an error (default: a warning; the recording's is used)");
  command.add_flag("--force-geometry", options.force_geometry,
                   "Use a handle radius the recording states outside 0.05 to 2 m");
  command.add_flag("--overwrite", options.overwrite,
                   "Write into an --out folder that exists and is not empty (files of the same "
                   "names are replaced)");
}

std::vector<std::filesystem::path> fit_input_paths(const FitDataOptions& options) {
  std::vector<std::filesystem::path> inputs{options.data_path};
  if (!options.model.params_path.empty()) inputs.emplace_back(options.model.params_path);
  if (options.model.effects_path.ends_with(".json"))
    inputs.emplace_back(options.model.effects_path);
  return inputs;
}

void check_handle_radius(const PreparedData& data, bool force_geometry) {
  if (force_geometry || data.handle_radius_m <= 0) return;  // 0: not stated
  const std::string origin = handle_radius_origin(data).empty()
                                 ? "the geometry calibration record " + data.geometry_calibration_id
                                 : handle_radius_origin(data);
  if (std::string problem = handle_radius_problem(data.handle_radius_m, origin); !problem.empty()) {
    throw UsageError("handle radius " + problem + "; give --force-geometry to use it anyway");
  }
}

FitInputs prepare_fit_run(const FitDataOptions& options, const std::filesystem::path& out_dir) {
  check_output_folder(out_dir, fit_input_paths(options), options.overwrite);
  FitInputs inputs = load_fit_inputs(options);
  std::filesystem::create_directories(out_dir);
  return inputs;
}

void list_excluded(PreparedData& data, const DoorModel& start,
                   std::vector<std::string>& report_lines) {
  WindowOptions windows = metric_window_options(FitOptions{}, start);
  windows.disjoint = FitOptions{}.estimate_window_states;  // as the window fit cuts them
  for (ExcludedSegment& window : gap_window_exclusions(data, windows)) {
    data.excluded.push_back(std::move(window));
  }
  std::stable_sort(
      data.excluded.begin(), data.excluded.end(),
      [](const ExcludedSegment& a, const ExcludedSegment& b) { return a.start_s < b.start_s; });
  std::cerr << "  " << data.strokes.size() << " strokes, " << data.excluded.size()
            << " segments excluded\n"
            << "  " << data.rate_summary << "\n";
  for (const std::string& warning : data.warnings) std::cerr << "warning: " << warning << "\n";
  if (data.excluded.empty()) return;
  std::string report = "excluded (" + std::to_string(data.excluded.size()) + "):";
  for (std::size_t k = 0; k < data.excluded.size(); ++k) {
    const ExcludedSegment& e = data.excluded[k];
    char span[80];
    std::snprintf(span, sizeof span, "%.3f s to %.3f s", e.start_s, e.end_s);
    const std::string line = "excluded " + std::string(span) + ": " + e.reason;
    if (k < kExcludedListed) std::cerr << "  " << line << "\n";
    report += "\n- " + line;
  }
  if (data.excluded.size() > kExcludedListed) {
    std::cerr << "  ... and " << data.excluded.size() - kExcludedListed
              << " more excluded segments (report.md and result.json list every one)\n";
  }
  report_lines.push_back(report);
}

FitInputs load_fit_inputs(const FitDataOptions& options) {
  std::cerr << "preparing " << options.data_path << "\n";
  PreparedData data = load_prepared_data(options.data_path, options.preprocessing);
  check_handle_radius(data, options.force_geometry);
  DoorModel start =
      start_model(options.model.model, options.model.params_path, options.model.effects_path);
  std::vector<std::string> report_lines;
  list_excluded(data, start, report_lines);
  for (const std::string& warning : data.warnings) {
    if (warning.starts_with(kCutShortWarning) || warning.starts_with(kUnitDoubtWarning)) {
      report_lines.push_back("warning: " + warning);
    }
  }
  const double file_radius_m = start.geometry().handle_radius_m;
  if (data.handle_radius_m > 0 &&
      std::abs(data.handle_radius_m - file_radius_m) > 1e-6 * file_radius_m) {
    // The recording's geometry (a calibrated bench's, or what the recording states), not
    // the door file's nominal radius.
    if (!options.model.params_path.empty()) {
      const std::string difference =
          "the door file's handle radius " + format_number(file_radius_m) + " m (" +
          options.model.params_path + ") differs from the recording's " +
          format_number(data.handle_radius_m) + " m, from " + handle_radius_origin(data);
      if (options.strict_geometry) {
        throw std::runtime_error(difference + " (--strict-geometry)");
      }
      const std::string warning = "warning: " + difference + "; the door file's handle radius " +
                                  format_number(file_radius_m) +
                                  " m is replaced (--strict-geometry makes this an error)";
      std::cerr << "  " << warning << "\n";
      report_lines.push_back(warning);
    }
    DoorGeometry geometry = start.geometry();
    geometry.handle_radius_m = data.handle_radius_m;
    const std::span<const double> values = start.parameter_values();
    const std::span<const Bounds> bounds = start.parameter_bounds();
    const auto base = static_cast<std::size_t>(start.base_parameter_count());
    start = DoorModel(start.kind(), geometry, {values.begin(), values.begin() + base},
                      {bounds.begin(), bounds.begin() + base},
                      {start.effects().begin(), start.effects().end()});
  }
  std::cerr << "  " << handle_radius_line(data, start) << "\n";

  const std::string base_name =
      options.model.params_path.empty() ? "the reference door" : options.model.params_path;
  std::vector<std::string> origin(static_cast<std::size_t>(start.base_parameter_count()),
                                  base_name);
  const bool from_data =
      options.start == "data" || (options.start == "auto" && options.model.params_path.empty());
  std::string start_line;
  if (from_data && start.kind() == ModelKind::kSensory) {
    const DataStart derived = start_from_data(data, start);
    start = derived.model;
    std::vector<std::string> data_names, latch_names, scaled_names;
    for (std::size_t i = 0; i < derived.origin.size(); ++i) {
      const std::string& name = start.parameter_name(static_cast<int>(i));
      if (derived.origin[i] == "free motion") {
        data_names.push_back(name);
        origin[i] = "the data (free motion)";
      } else if (derived.origin[i] == "latch read-off") {
        latch_names.push_back(name);
        origin[i] = "the data (latch read-off)";
      } else if (derived.origin[i] == "latch scaled") {
        scaled_names.push_back(name);
        origin[i] = "scaled to the latch read off";
      }
    }
    auto join = [](const std::vector<std::string>& names) {
      std::string text;
      for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
      return text;
    };
    start_line = "start values from the data";
    if (!data_names.empty()) {
      start_line += ": " + join(data_names) + " from " +
                    std::to_string(derived.free_motion_samples) +
                    " samples of free motion (balance torque " +
                    format_number(std::round(derived.balance_torque_Nm * 1000.0) / 1000.0) +
                    " N*m, force offset " +
                    format_number(std::round(derived.force_offset_N * 1000.0) / 1000.0) + " N)";
    }
    if (!latch_names.empty()) {
      start_line += std::string(data_names.empty() ? ": " : "; ") + join(latch_names) +
                    " read off the force-angle curves near closed";
    }
    if (!scaled_names.empty()) {
      start_line += "; " + join(scaled_names) + " scaled to the latch read off";
    }
    start_line += "; the others " + base_name + "'s";
    for (const std::string& note : derived.notes) start_line += "; " + note;
  } else if (from_data) {
    start_line =
        "start values: " + base_name + "'s (start values from the data: the sensory model only)";
  } else {
    start_line = "start values: " + base_name + "'s";
  }
  std::cerr << "  " << start_line << "\n";
  report_lines.push_back(start_line);
  return {.data = std::move(data),
          .start = std::move(start),
          .report_lines = std::move(report_lines),
          .start_origin = std::move(origin)};
}

std::string handle_radius_line(const PreparedData& data, const DoorModel& model) {
  std::ostringstream line;
  line << "handle radius " << model.geometry().handle_radius_m << " m, from ";
  const std::string origin = handle_radius_origin(data);
  line << (origin.empty() ? "the door parameter file" : origin);
  return line.str();
}

}  // namespace doorbench::app
