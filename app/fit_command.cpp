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
#include "analysis/fit/fit_result_file.h"
#include "analysis/fit/fit_windows.h"
#include "analysis/fit/fitting.h"
#include "analysis/model/parameter_file.h"
#include "analysis/report/svg_plot.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/fit_output.h"
#include "app/number_options.h"
#include "app/progress.h"
#include "app/stop_signals.h"
#include "core/number_format.h"

namespace doorbench::app {
namespace {

struct FitCommandOptions {
  FitDataOptions input;
  std::string free;
  std::string fixed;
  std::string objective = "windows";
  int folds = 4;
  int hops = kDefaultHops;  // FitOptions::global_hops
  bool no_reset = false;    // !FitOptions::global_reset
  bool no_soft = false;     // FitOptions::global_soft_switches empty
  int repolish = FitOptions{}.global_repolish;
  // The window fit's size: more windows than this, and whole strokes spread evenly over
  // the recording are kept (fit_size). 0: every window.
  int max_windows = kDefaultMaxWindows;
  bool init_only = false;
  std::string out_dir;

  // A few minutes of window fit on the two-core machine at most: a sensory fit of 54 windows
  // at 1 kHz took 1.6 s of CPU for 101 iterations, 0.3 ms per window and iteration, so 5000
  // windows take at most about 2.5 min of CPU for 100 iterations (docs/fitting.md, "The fit's
  // size").
  static constexpr int kDefaultMaxWindows = 5000;
  // None by default: on the fit study's 27 recordings 6 hops of 2 % of each bound's range
  // lowered the cost on 8 (7 by 0.1-6.7 %, one by 86 %) at about twice the global stage's CPU,
  // and lowered the fits from the true door as much (docs/PERFORMANCE.md, "Basin hops").
  static constexpr int kDefaultHops = 0;
  static constexpr double kHopSize = 0.02;
};

// The window fit's size, said before it starts, since every iteration's time grows with it
// (docs/fitting.md, "The fit's size"): its windows, as the fit cuts them. With more than
// max_windows (> 0), whole pairs of consecutive strokes are kept evenly over the recording
// (the first pair, the last and others evenly between), about as many as keep the windows at
// most max_windows (from the share of them, then fewer until they do), at least one pair;
// the others are left out, and the line says so. Returns the line (for stderr and the report).
std::string fit_size(PreparedData& data, const DoorModel& start, const FitOptions& fit,
                     int max_windows) {
  WindowOptions windows = metric_window_options(fit, start);
  windows.disjoint = fit.estimate_window_states;  // as the window fit cuts them
  const auto count_windows = [&windows](const PreparedData& d) {
    return split_windows(d, windows).size();
  };
  const std::size_t all = count_windows(data);
  const std::size_t strokes = data.strokes.size();
  const std::string window_text = "windows of " + format_number(fit.window_s) + " s";
  if (max_windows <= 0 || all <= static_cast<std::size_t>(max_windows) || strokes <= 2) {
    // Windows that span a recording gap are not in the count; say how many (listed above).
    const std::size_t across = split_windows_and_gaps(data, windows).across_gaps.size();
    return "the window fit: " + std::to_string(all) + " " + window_text + " on " +
           std::to_string(strokes) + " strokes" +
           (across == 0
                ? std::string()
                : std::string(" (")
                      .append(std::to_string(across))
                      .append(across == 1 ? " window spans a recording gap and is left out)"
                                          : " windows span a recording gap and are left out)"));
  }
  // The most pairs of consecutive strokes (an opening and its closing, so that both
  // directions stay in the fit), spread evenly, whose windows stay within max_windows.
  const std::vector<Stroke> every = std::move(data.strokes);
  const std::size_t pairs = (strokes + 1) / 2;
  for (std::size_t keep = std::max<std::size_t>(1, pairs * max_windows / all);; --keep) {
    data.strokes.clear();
    for (std::size_t j = 0; j < keep; ++j) {
      const std::size_t pair = keep == 1 ? 0 : j * (pairs - 1) / (keep - 1);
      for (std::size_t s = 2 * pair; s < std::min(2 * pair + 2, strokes); ++s) {
        data.strokes.push_back(every[s]);
      }
    }
    if (keep == 1 || count_windows(data) <= static_cast<std::size_t>(max_windows)) break;
  }
  const std::size_t kept_strokes = data.strokes.size();
  return "the window fit: " + std::to_string(count_windows(data)) + " " + window_text + " on " +
         std::to_string(kept_strokes) + " of the " + std::to_string(strokes) +
         " strokes, spread evenly over the recording (all " + std::to_string(all) +
         " windows would exceed --max-windows " + std::to_string(max_windows) +
         (count_windows(data) > static_cast<std::size_t>(max_windows)
              ? "; one pair of strokes is the least the fit takes)"
              : ")");
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

// --free auto (docs/fitting.md, "Identifiable parameters"): the default free set (less
// --fixed) is fitted once without folds (the full fit); when it leaves parameters
// undetermined, its identifiable set (FitSummary::identifiable) is refitted from the full
// fit's optimum with the others held there, and what that fit still leaves undetermined is
// held too (at most twice more). Each choice, and what holding the others costs in window FIT,
// is said on stderr and in the report. Throws std::runtime_error when no parameter is
// identifiable.
FitResult fit_free_auto(const DoorModel& start, const PreparedData& data, FitOptions fit,
                        StatusLine& status, std::vector<std::string>& report_lines) {
  auto say = [&](const std::string& line) {
    status.line(line);  // a line that stays, above the fit's status line
    report_lines.push_back(line);
  };
  FitOptions trial_options = fit;
  trial_options.cross_validation_folds = 0;
  trial_options.partial_on_stop = false;       // a trial is whole or not at all
  trial_options.what_would_determine = false;  // its report is not shown
  const FitResult full = fit_model(start, data, trial_options);
  const FitSummary& trial = full.summary;
  const std::size_t count = trial.free_names.size();
  if (trial.undetermined.empty()) {
    say("--free auto: the default free set's " + std::to_string(count) +
        " parameters are all determined; it is fitted as it is");
    fit.free_parameters = trial.free_names;
    return fit_model(start, data, fit);
  }
  if (trial.identifiable.empty()) {
    throw std::runtime_error("fit --free auto: the default free set leaves " +
                             joined(trial.undetermined) +
                             " undetermined and no subset of it is determined; give --free");
  }
  std::vector<std::string> held;
  for (const std::string& name : trial.free_names) {
    if (std::find(trial.identifiable.begin(), trial.identifiable.end(), name) ==
        trial.identifiable.end()) {
      held.push_back(name);
    }
  }
  say("--free auto: the default free set leaves " + std::to_string(trial.undetermined.size()) +
      " of its " + std::to_string(count) + " parameters undetermined (" +
      joined(trial.undetermined) + "); fitting the " + std::to_string(trial.identifiable.size()) +
      " the data determine with the others held (from the Jacobian's singular vectors at its "
      "optimum): " +
      joined(trial.identifiable) + "; held at the full fit's values: " + joined(held));
  // From the full fit's optimum: the values held are the fit's, and the free ones start
  // where the full fit left them (no read-off, no equation-error stage, one start).
  fit.free_parameters = trial.identifiable;
  fit.latch_start_from_data = false;
  fit.equation_error_start = false;
  fit.global_search = false;
  FitResult result = fit_model(full.model, data, fit);
  for (int round = 0;
       round < 2 && !result.summary.undetermined.empty() && result.summary.interrupted.empty();
       ++round) {
    const std::vector<std::string> still = result.summary.undetermined;
    std::erase_if(fit.free_parameters, [&still](const std::string& name) {
      return std::find(still.begin(), still.end(), name) != still.end();
    });
    if (fit.free_parameters.empty()) break;
    say("--free auto: that fit leaves " + joined(still) + " undetermined; refitting with " +
        (still.size() == 1 ? "it" : "them") + " held at the full fit's value" +
        (still.size() == 1 ? "" : "s"));
    result = fit_model(full.model, data, fit);
  }
  const double full_fit = trial.fitted.window.fit_percent();
  const double set_fit = result.summary.fitted.window.fit_percent();
  say("--free auto: holding the others costs " + printf_text("%.2f", full_fit - set_fit) +
      " points of window FIT (the full fit " + printf_text("%.2f%%", full_fit) + ", this fit " +
      printf_text("%.2f%%", set_fit) + ")");
  return result;
}

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

// report.md: the outcome first (what stopped the fit, when something did; the warnings about
// the data among the notes), then how the data were read and the fit set up, the full report, the
// residual's whiteness and the plots.
std::string fit_report_page(const std::string& model_name, const FitInputs& inputs,
                            const FitResult& result, const FitPlots& plots,
                            const std::string& interrupted) {
  std::ostringstream page;
  page << "# Fit of the " << model_name << " model to " << inputs.data.source << "\n\n"
       << "## Result\n\n";
  if (!interrupted.empty()) page << "**" << interrupted << ".**\n\n";
  std::istringstream headline(result.summary.headline());
  for (std::string line; std::getline(headline, line);) page << line << "\n\n";
  for (const std::string& line : inputs.report_lines) {
    if (line.starts_with("warning: ")) page << line << ".\n\n";
  }
  page << "## The data and the fit's set-up\n\n";
  for (const std::string& line : inputs.report_lines) {
    if (!line.starts_with("warning: ")) page << line << ".\n\n";
  }
  page << "Data: " << inputs.data.rate_summary << ".\n\n"
       << handle_radius_line(inputs.data, result.model) << ".\n\n"
       << "## In full\n\n"
       << "```\n"
       << result.summary.full_report() << "```\n\n"
       << "The fitted model's " << plots.whiteness << ".\n\n";
  if (!plots.files.empty()) page << "## Plots\n\n";
  for (const std::string& plot : plots.files) page << "![" << plot << "](" << plot << ")\n\n";
  return page.str();
}

void run_fit(const FitCommandOptions& options) {
  // SIGINT/SIGTERM: the fit ends at its next solver iteration. A whole window fit is written,
  // marked interrupted (without what the stop cut: held-out metrics); before that
  // there is nothing to write. A second signal ends doorbench at once.
  const StopSignals signals;
  // Before any reading: a parameter is free or held, not both.
  for (const std::string& name : split_names(options.free)) {
    const std::vector<std::string> fixed = split_names(options.fixed);
    if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) {
      throw UsageError("--free and --fixed both name " + name + " (a parameter is free or held)");
    }
  }
  // The names, against the start model's parameters (effects included), before the data.
  const DoorModel named = start_model(options.input.model.model, options.input.model.params_path,
                                      options.input.model.effects_path);
  const bool free_auto = options.free == "auto";
  if (!free_auto) check_parameter_names(named, "--free", split_names(options.free));
  check_parameter_names(named, "--fixed", split_names(options.fixed));
  FitInputs inputs = prepare_fit_run(options.input, options.out_dir);
  if (signals.received() != 0) {
    throw nothing_finished(signals.received(), "fit", "the fit", "the reading of its data",
                           options.out_dir);
  }
  const PreparedData& data = inputs.data;
  const DoorModel& start = inputs.start;
  if (options.init_only) {
    remove_whole_fit_outputs(options.out_dir);
    write_start(options.out_dir, inputs);
    std::cout << "start-params.json and start.md are in " << options.out_dir << "/\n";
    return;
  }

  FitOptions fit_options;
  fit_options.substeps_per_sample = substeps_for_1ms_steps(data);
  if (!free_auto) fit_options.free_parameters = split_names(options.free);
  fit_options.fixed_parameters = split_names(options.fixed);
  if (options.objective == "study-max") {
    fit_options.objective = FitOptions::Objective::kWholeStrokeMax;
  }
  fit_options.cross_validation_folds = options.folds;
  fit_options.global_hops = options.hops;
  fit_options.global_hop_size = FitCommandOptions::kHopSize;
  fit_options.global_reset = !options.no_reset;
  fit_options.global_repolish = options.repolish;
  if (options.no_soft) fit_options.global_soft_switches.clear();
  const std::string size = fit_size(inputs.data, start, fit_options, options.max_windows);
  std::cerr << size << "\n";
  inputs.report_lines.push_back(size);
  StatusLine status(std::cerr, stderr_is_terminal(), 5.0, stderr_terminal_columns());
  status.line("fitting the " + options.input.model.model + " model" +
              (options.folds > 0
                   ? " (with " + std::to_string(options.folds) + "-fold cross-validation)"
                   : ""));
  fit_options.progress = fit_progress_display(status);
  fit_options.stop_requested = [&signals] { return signals.received() != 0; };
  fit_options.partial_on_stop = true;
  FitResult result{start, FitSummary{}, {}};
  try {
    result = free_auto ? fit_free_auto(start, data, fit_options, status, inputs.report_lines)
                       : fit_model(start, data, fit_options);
  } catch (const StopRequested& stop) {
    status.finish();
    throw nothing_finished(signals.received(), "fit", "the fit", stop.where(), options.out_dir);
  }
  status.finish();
  const std::string interrupted =
      result.summary.interrupted.empty()
          ? ""
          : signal_name(signals.received()) + " stopped the fit " + result.summary.interrupted;

  const std::filesystem::path dir = options.out_dir;
  remove_start_outputs(dir);
  write_text_file_atomically(dir / "result.json", fit_result_json(result, data));
  write_text_file_atomically(dir / "fitted-params.json", to_parameter_json(result.model));
  if (result.model.effects().empty()) {
    remove_output_not_written(dir / "fitted-effects.json");
  } else {
    write_text_file_atomically(dir / "fitted-effects.json", to_effects_json(result.model));
  }
  FitPlots plots = write_fit_plots(dir, result.model, data, fit_options);
  if (const std::string optima = write_global_search_plot(dir, result.summary); !optima.empty()) {
    plots.files.push_back(optima);
  }
  write_text_file_atomically(dir / "report.md", fit_report_page(options.input.model.model, inputs,
                                                                result, plots, interrupted));
  std::cout << result.summary.brief_report() << "\nresult.json, report.md, fitted-params.json and "
            << "plots are in " << dir.string() << "/\n";
  if (!interrupted.empty()) {
    throw Interrupted(signals.received(), "fit: " + interrupted + "; the results in " +
                                              dir.string() + "/ are marked interrupted");
  }
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
                  "Free parameters, comma-separated (default: docs/fitting.md); auto: the "
                  "default set fitted once, then only the parameters its data determine, "
                  "refitted from there with the others held at that fit's values");
  fit->add_option("--fixed", options->fixed, "Parameters held at their start values");
  fit->add_option("--objective", options->objective,
                  "windows (least squares on windows) or study-max (the study's largest rate "
                  "error over whole strokes, started from the windows fit)")
      ->check(CLI::IsMember({"windows", "study-max"}))
      ->capture_default_str();
  fit->add_option("--folds", options->folds, "Cross-validation folds over strokes (0: none)")
      ->check(number_range(0, 1000))
      ->capture_default_str();
  fit->add_option("--hops", options->hops,
                  "Basin hops after the global stage: random steps from the best optimum so "
                  "far, each polished: lower costs at a polish each (docs/fitting.md)")
      ->check(number_range(0, 1000))
      ->capture_default_str();
  fit->add_flag("--no-reset", options->no_reset,
                "Leave out the global stage's reset start (the first optimum with its "
                "undetermined or bound parameters at their starts): one polish less, and a "
                "basin only it reaches is missed (docs/fitting.md)");
  fit->add_flag("--no-soft", options->no_soft,
                "Leave out the global stage's fits with softer switches (the data-derived "
                "start fitted with the latch's switches 10 and 3 times softer, each then "
                "polished): less CPU, and a basin only they reach is missed (docs/fitting.md)");
  fit->add_option("--repolish", options->repolish,
                  "Polish the global stage's best optimum again from its own values, at most "
                  "this many times, while each polish lowers it by more than 0.1 % (0: never: "
                  "faster, and a lower point of a rough cost floor may be missed; "
                  "docs/fitting.md)")
      ->check(number_range(0, 1000))
      ->capture_default_str();
  fit->add_option("--max-windows", options->max_windows,
                  "Most windows in the window fit: beyond, whole strokes spread evenly over the "
                  "recording are fitted (0: every window)")
      ->check(number_range(0, 100000000))
      ->capture_default_str();
  fit->add_flag("--init-only", options->init_only,
                "Only write the start: start-params.json (a parameter file) and start.md "
                "(where each value came from)");
  fit->add_option("--out", options->out_dir, "Folder for result.json, report.md and plots")
      ->required();
  fit->callback([options, &action] { action = [options] { run_fit(*options); }; });
}

}  // namespace doorbench::app
