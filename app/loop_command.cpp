// doorbench loop: fit, look at the residual, add the effect the model lacks, refit, and
// report the error before and after each step (analysis/loop/residual_loop.h).
#include <filesystem>
#include <iostream>
#include <memory>

#include "analysis/loop/residual_loop.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/loop_output.h"
#include "app/progress.h"

namespace doorbench::app {
namespace {

struct LoopCommandOptions {
  FitDataOptions input;
  int folds = 3;
  int max_steps = 4;
  std::string out_dir;
};

void run_loop(const LoopCommandOptions& options) {
  const FitInputs inputs = prepare_fit_run(options.input, options.out_dir);
  LoopOptions loop_options;
  loop_options.fit.cross_validation_folds = options.folds;
  loop_options.fit.substeps_per_sample = substeps_for(inputs.data);
  loop_options.max_steps = options.max_steps;
  // Stage lines stay; the start fit's, the steps' and the structure check's progress is a
  // status line with the time left (app/progress.h).
  StatusLine status(std::cerr, stderr_is_terminal(), 5.0, stderr_terminal_columns());
  loop_options.progress = [&status](const std::string& line) { status.line(line); };
  loop_options.fit.progress = fit_progress_display(status);
  loop_options.step_progress = loop_progress_display(status);
  const LoopResult result = run_residual_loop(inputs.start, inputs.data, loop_options);
  status.finish();
  const std::string table =
      write_loop_outputs(options.out_dir, result, inputs.data, options.input.model.model,
                         loop_options.fit, inputs.report_lines);
  std::cout << result.brief_report() << "\n"
            << table << "\nresult.json, report.md, the fitted "
            << "parameter and effects files and plots are in " << options.out_dir << "/\n";
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
      ->check(CLI::Range(3, 1000))
      ->capture_default_str();
  loop->add_option("--max-steps", options->max_steps, "Most effects to add")
      ->check(CLI::Range(1, 8))
      ->capture_default_str();
  loop->add_option("--out", options->out_dir, "Folder for result.json, report.md and plots")
      ->required();
  loop->callback([options, &action] { action = [options] { run_loop(*options); }; });
}

}  // namespace doorbench::app
