// doorbench spec: the design specification from TO-BE recordings and the AS-IS door —
// inverse design, felt quantities before/after, the check, tolerances, spec.json/html/pdf
// (analysis/design/specify.h does it; this file parses and prints).
#include <iostream>
#include <map>
#include <optional>

#include "analysis/design/specify.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/progress.h"
#include "app/spec_campaign.h"
#include "app/spec_run.h"
#include "app/stop_signals.h"
#include "study/statistics/analysis_for_spec.h"

namespace doorbench::app {
namespace {

// "F0=1,k_s=5" into `weights` (each entry replacing the default). Throws UsageError naming
// the entry that is not NAME=COST with a number.
void parse_costs(const std::string& list, std::map<std::string, double>& weights) {
  for (const std::string& entry : split_names(list)) {
    const std::size_t equals = entry.find('=');
    std::size_t used = 0;
    double cost = 0.0;
    try {
      if (equals != std::string::npos) cost = std::stod(entry.substr(equals + 1), &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (equals == std::string::npos || equals == 0 || used == 0 ||
        used != entry.size() - equals - 1) {
      throw UsageError("--costs: '" + entry + "' is not NAME=COST (e.g. F0=1)");
    }
    weights[entry.substr(0, equals)] = cost;
  }
}

std::string describe(const SpecCommandOptions& o) {
  std::string text = "doorbench spec";
  for (const std::string& path : o.tobe_paths) text += " " + path;
  text += " --asis " + o.asis_path + " --out " + o.out_dir;
  if (!o.asis_recording.empty()) text += " --asis-recording " + o.asis_recording;
  if (o.fixed_given) text += " --fixed " + (o.fixed.empty() ? std::string("''") : o.fixed);
  if (!o.costs.empty()) text += " --costs " + o.costs;
  if (!o.tolerances_path.empty()) text += " --tolerances " + o.tolerances_path;
  if (!o.campaign_dir.empty()) text += " --campaign " + o.campaign_dir;
  if (!o.felt_share.empty()) text += " --felt-share " + o.felt_share;
  text += " --samples " + std::to_string(o.samples) + " --seed " + std::to_string(o.seed);
  return text;
}

// The command line's options as the library's; UsageError for what it refuses
// (--felt-share without --campaign, SpecOptions::validate(), a share or cost that is not one).
SpecOptions spec_options(const SpecCommandOptions& o) {
  if (!o.felt_share.empty() && o.campaign_dir.empty()) {
    throw UsageError("--felt-share needs --campaign");
  }
  SpecOptions options;
  options.tobe_paths.assign(o.tobe_paths.begin(), o.tobe_paths.end());
  options.asis_path = o.asis_path;
  options.asis_recording = o.asis_recording;
  options.out_dir = o.out_dir;
  options.overwrite = o.overwrite;
  if (o.fixed_given) options.fixed = split_names(o.fixed);
  options.tolerances_path = o.tolerances_path;
  options.samples = o.samples;
  options.threads = o.threads;
  options.seed = o.seed;
  options.regularization = o.regularization;
  options.starts = o.starts;
  options.motion_only = o.motion_only;
  options.pdf = !o.no_pdf;
  options.tolerances = !o.no_tolerances;
  options.campaign_dir = o.campaign_dir;
  options.read_campaign = study::read_campaign_for_spec;
  options.command = describe(o);
  if (std::string problem = options.validate(); !problem.empty()) throw UsageError(problem);
  if (!o.felt_share.empty()) options.felt_share = parse_felt_share(o.felt_share);
  parse_costs(o.costs, options.costs);
  return options;
}

}  // namespace

void run_spec(const SpecCommandOptions& command) {
  SpecOptions options = spec_options(command);
  // SIGINT/SIGTERM: the fits end at their next solver iteration, the Monte Carlo at its next
  // sample. Before the design is whole there is nothing to write; after, the specification is
  // written without what the stop cut, marked interrupted. A second signal ends doorbench.
  const StopSignals signals;
  options.stop_requested = [&signals] { return signals.received() != 0; };
  std::optional<StatusLine> status;
  if (command.show_progress) {
    status.emplace(std::cerr, stderr_is_terminal(), 5.0, stderr_terminal_columns());
    options.progress = [&status](const std::string& line) { status->line(line); };
    // The samples' status line, with the time left (app/progress.h).
    options.monte_carlo_progress =
        count_progress_display(*status, "tolerance Monte Carlo", "samples");
  }
  SpecSummary summary;
  try {
    summary = specify(options);
  } catch (const SpecOptionsError& error) {
    throw UsageError(error.what());
  } catch (const StopRequested& stopped) {
    throw nothing_finished(signals.received(), "spec", "the specification", stopped.where(),
                           command.out_dir);
  }
  if (status) status->finish();
  if (summary.pdf_interrupted) {
    throw Interrupted(signals.received(),
                      "spec: " + signal_name(signals.received()) +
                          " stopped the specification during the PDF rendering: no spec.pdf; "
                          "spec.json, spec.html and tobe-params.json in " +
                          command.out_dir + "/ are complete");
  }
  std::cout << summary.brief_report();
  if (!summary.evaluation.interrupted.empty()) {
    throw Interrupted(signals.received(), "spec: " + signal_name(signals.received()) +
                                              " stopped the specification " +
                                              summary.evaluation.interrupted + "; the results in " +
                                              command.out_dir + "/ are marked interrupted");
  }
}

void add_spec_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<SpecCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "spec",
      "Design specification: the physical door that feels like the TO-BE recordings with the "
      "smallest change to the AS-IS door, checked, with its tolerances (spec.json, spec.html, "
      "spec.pdf when weasyprint is installed)");
  command
      ->add_option("TOBE_SESSIONS", options->tobe_paths,
                   "TO-BE recordings (sessions or CSV), e.g. haptic playback sessions; "
                   "optional with --campaign")
      ->check(CLI::ExistingFile);
  command
      ->add_option("--asis", options->asis_path,
                   "AS-IS door: a physical parameter file or a `doorbench fit` folder")
      ->required();
  command
      ->add_option("--asis-recording", options->asis_recording,
                   "a recording of the AS-IS door on the same bench: the AS-IS door is first "
                   "corrected to it (the bench's own effects stay out of the design)")
      ->check(CLI::ExistingFile);
  command->add_option("--out", options->out_dir, "folder for the report")->required();
  command->add_flag("--overwrite", options->overwrite,
                    "write into an --out folder that exists and is not empty");
  command
      ->add_option("--fixed", options->fixed,
                   "comma-separated parameters kept at their AS-IS values (default: m_d, l_c, "
                   "J_d and the modelling devices k_stop, c_stop, e, w_f)")
      ->each([options](const std::string&) { options->fixed_given = true; });
  command->add_option("--costs", options->costs,
                      "costs of change overriding the defaults, e.g. F0=1,k_s=5 (a parameter "
                      "the data cannot tell from another: the cheaper one is changed)");
  CLI::Option* tolerances =
      command
          ->add_option("--tolerances", options->tolerances_path,
                       "tolerance file overriding the defaults (docs/design-spec.md)")
          ->check(CLI::ExistingFile);
  command->add_option("--samples", options->samples, "Monte Carlo samples")->capture_default_str();
  command->add_option("--threads", options->threads, "threads for the Monte Carlo (0: all cores)")
      ->capture_default_str();
  command->add_option("--seed", options->seed, "Monte Carlo seed")->capture_default_str();
  command
      ->add_option("--lambda", options->regularization,
                   "how strongly the smallest change is preferred")
      ->capture_default_str();
  command->add_option("--starts", options->starts, "inverse fits from different starts")
      ->capture_default_str();
  command->add_flag("--motion-only", options->motion_only,
                    "fit the recorded motion even when the sessions carry the torque a haptic "
                    "playback commanded");
  command->add_flag("--no-pdf", options->no_pdf, "do not render spec.pdf");
  // Either would be ignored with --no-tolerances, so either with it is refused.
  CLI::Option* samples = command->get_option("--samples");
  command->add_flag("--no-tolerances", options->no_tolerances, "skip the tolerance analysis")
      ->excludes(tolerances)
      ->excludes(samples);
  command->add_option("--campaign", options->campaign_dir,
                      "a `doorbench campaign analyze` folder (analysis.json): the TO-BE feel "
                      "from the panel when no recordings are given, and tolerances judged by "
                      "the panel's JNDs (docs/design-spec.md)");
  command->add_option("--felt-share", options->felt_share,
                      "with --campaign: the largest share of manufactured doors a panel member "
                      "may feel as different, as percent (5%) or fraction (0.05); default 5%");
  command->callback([options, &action] { action = [options] { run_spec(*options); }; });
}

}  // namespace doorbench::app
