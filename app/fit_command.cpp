// doorbench fit: a door model fitted to a session or a CSV, with its report.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>

#include "acquisition/session/output_file.h"
#include "analysis/fit/fit_metrics.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/report/svg_plot.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/fit_output.h"
#include "app/progress.h"
#include "core/number_format.h"

namespace doorbench::app {
namespace {

struct FitCommandOptions {
  FitDataOptions input;
  std::string free;
  std::string fixed;
  std::string objective = "windows";
  int folds = 4;
  bool init_only = false;
  std::string out_dir;
};

// --init-only: the start parameter file and a page saying where each value came from.
void write_start(const std::filesystem::path& dir, const FitInputs& inputs) {
  write_text_file_atomically(dir / "start-params.json", to_parameter_json(inputs.start));
  std::ostringstream page;
  page << "# Start values for " << inputs.data.source << "\n\n";
  for (const std::string& line : inputs.report_lines) page << line << ".\n\n";
  page << "Data: " << inputs.data.rate_summary << ".\n\n"
       << handle_radius_line(inputs.data, inputs.start) << ".\n\n"
       << "| parameter | start | lower | upper | from |\n|---|---|---|---|---|\n";
  const auto values = inputs.start.parameter_values();
  const auto bounds = inputs.start.parameter_bounds();
  for (std::size_t i = 0; i < inputs.start_origin.size(); ++i) {
    page << "| " << inputs.start.parameter_name(static_cast<int>(i)) << " | "
         << format_number(values[i]) << " | " << format_number(bounds[i].lower) << " | "
         << format_number(bounds[i].upper) << " | " << inputs.start_origin[i] << " |\n";
  }
  write_text_file_atomically(dir / "start.md", page.str());
}

void run_fit(const FitCommandOptions& options) {
  // Before any reading: a parameter is free or held, not both (issue 33).
  for (const std::string& name : split_names(options.free)) {
    const std::vector<std::string> fixed = split_names(options.fixed);
    if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) {
      throw UsageError("--free and --fixed both name " + name + " (a parameter is free or held)");
    }
  }
  // The names, against the start model's parameters (effects included), before the data.
  const DoorModel named = start_model(options.input.model.model, options.input.model.params_path,
                                      options.input.model.effects_path);
  check_parameter_names(named, "--free", split_names(options.free));
  check_parameter_names(named, "--fixed", split_names(options.fixed));
  const FitInputs inputs = prepare_fit_run(options.input, options.out_dir);
  const PreparedData& data = inputs.data;
  const DoorModel& start = inputs.start;
  if (options.init_only) {
    write_start(options.out_dir, inputs);
    std::cout << "start-params.json and start.md are in " << options.out_dir << "/\n";
    return;
  }

  FitOptions fit_options;
  fit_options.substeps_per_sample = substeps_for(data);
  fit_options.free_parameters = split_names(options.free);
  fit_options.fixed_parameters = split_names(options.fixed);
  if (options.objective == "study-max") {
    fit_options.objective = FitOptions::Objective::kWholeStrokeMax;
  }
  fit_options.cross_validation_folds = options.folds;
  StatusLine status(std::cerr, stderr_is_terminal(), 5.0, stderr_terminal_columns());
  status.line("fitting the " + options.input.model.model + " model" +
              (options.folds > 0
                   ? " (with " + std::to_string(options.folds) + "-fold cross-validation)"
                   : ""));
  fit_options.progress = fit_progress_display(status);
  const FitResult result = fit_model(start, data, fit_options);
  status.finish();

  const std::filesystem::path dir = options.out_dir;
  write_text_file_atomically(dir / "result.json", fit_result_json(result, data).dump(2) + "\n");
  write_text_file_atomically(dir / "fitted-params.json", to_parameter_json(result.model));
  if (!result.model.effects().empty()) {
    write_text_file_atomically(dir / "fitted-effects.json", to_effects_json(result.model));
  }
  const FitPlots plots = write_fit_plots(dir, result.model, data, fit_options);
  std::ostringstream report;
  report << "# Fit of the " << options.input.model.model << " model to " << data.source << "\n\n";
  for (const std::string& line : inputs.report_lines) report << line << ".\n\n";
  report << "Data: " << data.rate_summary << ".\n\n"
         << handle_radius_line(data, result.model) << ".\n\n"
         << "```\n"
         << result.summary.full_report() << "```\n\n"
         << "The fitted model's " << plots.whiteness << ".\n\n";
  for (const std::string& plot : plots.files) report << "![" << plot << "](" << plot << ")\n\n";
  write_text_file_atomically(dir / "report.md", report.str());
  std::cout << result.summary.brief_report() << "\nresult.json, report.md, fitted-params.json and "
            << "plots are in " << dir.string() << "/\n";
}

}  // namespace

void add_fit_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<FitCommandOptions>();
  CLI::App* fit = app.add_subcommand(
      "fit",
      "Fit a door model to a session or a CSV recording: multiple shooting on short windows "
      "started from measured states (docs/fitting.md), with uncertainties, held-out metrics, "
      "a report and plots");
  add_fit_data_options(
      *fit, options->input,
      "Effects to add: an effects file (*.json) or names, e.g. stribeck,viscous_damping");
  fit->add_option("--free", options->free,
                  "Free parameters, comma-separated (default: docs/fitting.md)");
  fit->add_option("--fixed", options->fixed, "Parameters held at their start values");
  fit->add_option("--objective", options->objective,
                  "windows (least squares on windows) or study-max (the study's largest rate "
                  "error over whole strokes, started from the windows fit)")
      ->check(CLI::IsMember({"windows", "study-max"}))
      ->capture_default_str();
  fit->add_option("--folds", options->folds, "Cross-validation folds over strokes (0: none)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  fit->add_flag("--init-only", options->init_only,
                "Only write the start: start-params.json (a parameter file) and start.md "
                "(where each value came from)");
  fit->add_option("--out", options->out_dir, "Folder for result.json, report.md and plots")
      ->required();
  fit->callback([options, &action] { action = [options] { run_fit(*options); }; });
}

}  // namespace doorbench::app
