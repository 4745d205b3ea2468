// doorbench loop: fit, look at the residual, add the effect the model lacks, refit, and
// report the error before and after each step (analysis/loop/residual_loop.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/loop/residual_loop.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/loop_output.h"
#include "app/number_options.h"
#include "app/progress.h"
#include "app/stop_signals.h"

namespace doorbench::app {
namespace {

struct LoopCommandOptions {
  FitDataOptions input;
  int folds = 3;
  int max_steps = 4;
  std::string out_dir;
};

// The first line of an interrupted loop's report.md, and its message.
std::string interrupted_line(const LoopResult& result, int signal_number) {
  const std::size_t steps = result.steps.size();
  return signal_name(signal_number) + " stopped the loop: " + result.stop_reason + "; " +
         (steps == 0 ? std::string("no step was finished before it")
                     : std::string("the ")
                           .append(std::to_string(steps))
                           .append(steps == 1 ? " step" : " steps")
                           .append(" finished before it ")
                           .append(steps == 1 ? "is" : "are")
                           .append(result.structure.ran
                                       ? " kept, as is the structure check that ran before it"
                                       : " kept, the structure check was not run"));
}

void run_loop(const LoopCommandOptions& options) {
  // SIGINT/SIGTERM: the loop's fits end at their next solver iteration, and the steps finished
  // so far are written, marked interrupted; a second signal ends doorbench at once.
  const StopSignals signals;
  const FitInputs inputs = prepare_fit_run(options.input, options.out_dir);
  if (signals.received() != 0) {
    throw nothing_finished(signals.received(), "loop", "the loop", "the reading of its data",
                           options.out_dir);
  }
  LoopOptions loop_options;
  loop_options.fit.cross_validation_folds = options.folds;
  loop_options.fit.substeps_per_sample = substeps_for_1ms_steps(inputs.data);
  loop_options.max_steps = options.max_steps;
  // Stage lines stay; the start fit's, the steps' and the structure check's progress is a
  // status line with the time left (app/progress.h).
  StatusLine status(std::cerr, stderr_is_terminal(), 5.0, stderr_terminal_columns());
  loop_options.progress = [&status](const std::string& line) { status.line(line); };
  loop_options.fit.progress = fit_progress_display(status);
  loop_options.step_progress = loop_progress_display(status);
  loop_options.stop_requested = [&signals] { return signals.received() != 0; };
  std::optional<LoopResult> ran;
  try {
    ran = run_residual_loop(inputs.start, inputs.data, loop_options);
  } catch (const StopRequested& stop) {  // during the start model's fit: nothing finished
    status.finish();
    throw nothing_finished(signals.received(), "loop", "the loop",
                           stop.where() + " of the start model", options.out_dir);
  }
  const LoopResult& result = *ran;
  status.finish();
  std::vector<std::string> report_lines = inputs.report_lines;
  const int signal_number = signals.received();
  if (result.interrupted) {
    report_lines.insert(report_lines.begin(), interrupted_line(result, signal_number));
  }
  const std::string table =
      write_loop_outputs(options.out_dir, result, inputs.data, options.input.model.model,
                         loop_options.fit, report_lines);
  std::cout << result.brief_report() << "\n"
            << table << "\nresult.json, report.md, the fitted "
            << "parameter and effects files and plots are in " << options.out_dir << "/\n";
  if (result.interrupted) {
    throw Interrupted(signal_number, "loop: " + interrupted_line(result, signal_number) +
                                         "; the results in " + options.out_dir +
                                         "/ are marked interrupted");
  }
  if (signal_number != 0) {
    std::cerr << signal_name(signal_number)
              << " arrived after the loop's last stage: its result is complete\n";
  }
}

}  // namespace

void add_loop_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<LoopCommandOptions>();
  CLI::App* loop = app.add_subcommand(
      "loop",
      "Close the loop: fit, rank the effects of the catalogue by how much of the residual each "
      "explains, add the best only if it lowers the held-out error by more than 2% and BIC, "
      "refit, repeat (docs/residual-loop.md)");
  add_fit_data_options(*loop, options->input,
                       "Effects the start model already has (a *.json file or names)");
  loop->add_option("--folds", options->folds, "Cross-validation folds over strokes (>= 3)")
      ->check(number_range(3, 1000))
      ->capture_default_str();
  loop->add_option("--max-steps", options->max_steps, "Most effects to add")
      ->check(number_range(1, 8))
      ->capture_default_str();
  loop->add_option("--out", options->out_dir, "Folder for result.json, report.md and plots")
      ->required();
  loop->callback([options, &action] { action = [options] { run_loop(*options); }; });
}

}  // namespace doorbench::app
