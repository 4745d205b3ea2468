// doorbench spec: the design specification from TO-BE recordings and the AS-IS door —
// inverse design, felt quantities before/after, the check, tolerances, spec.json/html/pdf.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <thread>

#include "acquisition/session/output_file.h"
#include "analysis/design/equivalent_solutions.h"
#include "analysis/design/inverse_design.h"
#include "analysis/design/perceptual_tolerance.h"
#include "analysis/design/spec_report.h"
#include "analysis/design/tolerance_analysis.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/model/parameter_file.h"
#include "analysis/simulation/fit_synthetic.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/progress.h"
#include "app/spec_campaign.h"
#include "app/spec_run.h"
#include "app/stop_signals.h"
#include "core/number_format.h"

namespace doorbench::app {
namespace {

// Where progress goes when it is not wanted.
std::ostream& null_stream() {
  static std::ostream sink(nullptr);
  return sink;
}

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

// The AS-IS door as the bench sees it: `asis` corrected to its own recording by the sparse
// search (docs/inverse-design.md, "The AS-IS door as the bench sees it").
DoorModel asis_on_bench(const DoorModel& asis, const std::string& recording,
                        const InverseDesignOptions& design_options, std::ostream& progress) {
  progress << "AS-IS recording: " << recording << "\n";
  InverseDesignOptions options = design_options;
  options.smallest_change_alongside = false;
  const InverseDesignResult bench = inverse_design(asis, {load_prepared_data(recording)}, options);
  const DesignSolution& door = bench.solutions.front();
  std::string changes;
  for (const DesignParameter& p : door.parameters) {
    if (p.changed) {
      changes += " " + p.name + " " + format_number(p.as_is) + " -> " + format_number(p.to_be);
    }
  }
  progress << "the AS-IS door as this bench sees it:"
           << (changes.empty() ? " as its file" : changes) << "\n";
  return door.model;
}

// The warning for TO-BE recordings of a real door measured through a bench's sensors (the
// angle integrated from its gyroscope) without --asis-recording: the AS-IS parameter file
// is then compared with what the bench measured, and the bench's own deviations can come
// out as design changes (docs/inverse-design.md, "The AS-IS door as the bench sees it").
// "" when the recordings are haptic playbacks, not from a bench, or --asis-recording is
// given.
std::string bench_without_asis_recording(const std::vector<PreparedData>& tobe,
                                         bool playbacks, const SpecCommandOptions& options) {
  if (playbacks || !options.asis_recording.empty()) return "";
  std::string paths, how;
  for (std::size_t i = 0; i < tobe.size(); ++i) {
    if (tobe[i].angle_source.rfind("rate_rad_s integrated", 0) != 0) continue;
    paths += (paths.empty() ? "" : ", ") + options.tobe_paths[i];
    if (how.empty()) how = tobe[i].angle_source;
  }
  if (paths.empty()) return "";
  return "the TO-BE recording " + paths + " was measured through a bench's sensors (angle: " +
         how +
         ") and --asis-recording is not given: the AS-IS parameter file is compared with what "
         "the bench measured, so the bench's own deviations (sensor offsets and scales, the "
         "load cell's mounting, its friction) can be specified as design changes; record the "
         "AS-IS door on the same bench and give it as --asis-recording";
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

// The options of the TO-BE source and the campaign checked; --felt-share's value (5 %
// when not given). Throws UsageError.
double checked_felt_share(const SpecCommandOptions& options) {
  const bool from_campaign = !options.campaign_dir.empty();
  if (options.tobe_paths.empty() && !from_campaign) {
    throw UsageError("spec: give TO-BE recordings or --campaign FOLDER");
  }
  if (!options.felt_share.empty() && !from_campaign) {
    throw UsageError("--felt-share needs --campaign");
  }
  if (from_campaign && options.no_tolerances) {
    throw UsageError("--campaign needs the tolerance analysis: drop --no-tolerances");
  }
  return options.felt_share.empty() ? 0.05 : parse_felt_share(options.felt_share);
}

// The TO-BE feel with a campaign: without TO-BE recordings, the panel's door (the favourite
// variant or the tuned doors' centre) opened and closed by the virtual hand, as synthetic
// strokes with the bench's noise (fit_synthetic.h) appended to `tobe`. Returns what the
// report says of it.
std::string campaign_tobe(const CampaignForSpec& campaign, const DoorModel& asis,
                          std::vector<PreparedData>& tobe, std::ostream& progress) {
  for (const std::string& note : campaign.notes) progress << "campaign: " << note << "\n";
  if (!tobe.empty()) {
    return "the TO-BE recordings given; the campaign gives the JNDs and the panel's results";
  }
  std::string source;
  const DoorModel door = campaign_tobe_model(campaign, asis, source);
  progress << "TO-BE feel from the panel: " << source << "\n";
  PreparedData strokes = synthetic_strokes(door, {});
  strokes.source = "the panel's door (simulated strokes): " + campaign.analysis_path.string();
  tobe.push_back(std::move(strokes));
  return source;
}

// The panel's side of the specification: the shares felt as different at the tolerances
// the Monte Carlo used, and the proposal keeping them under the level.
PerceptualSpec perceptual_spec(const CampaignForSpec& campaign, const std::string& tobe_source,
                               double felt_share, const DoorModel& design,
                               const SpecEvaluationOptions& evaluation_options,
                               const ToleranceResult& given, std::ostream& progress) {
  PerceptualSpec p;
  p.campaign = campaign.analysis_path.string();
  p.tobe_source = tobe_source;
  p.notes = campaign.notes;
  p.preference = campaign.preference;
  p.thresholds = campaign.thresholds;
  p.jnds = campaign.jnds;
  p.rows = perceptual_shares(given, p.jnds);
  PerceptualToleranceOptions options;
  options.felt_share = felt_share;
  options.progress = [&progress](double factor, double worst) {
    progress << "  tolerances x " << format_significant(factor, 3) << ": largest share felt as "
             << "different " << format_significant(100 * worst, 3) << "%\n"
             << std::flush;
  };
  MonteCarloOptions monte_carlo = evaluation_options.monte_carlo;
  monte_carlo.felt = evaluation_options.felt;
  monte_carlo.progress = nullptr;
  progress << "perceptual tolerances: the common factor on every tolerance keeping each share "
              "felt as different under "
           << format_significant(100 * felt_share, 3) << "% (a Monte Carlo of "
           << monte_carlo.samples << " samples per factor tried)\n";
  const ToleranceSpec spec{given.tolerances};
  p.proposal = propose_perceptual_tolerances(design, spec, monte_carlo, p.jnds, options, &given);
  progress << "  " << p.proposal.summary << "\n";
  return p;
}

}  // namespace

// The TO-BE recordings, prepared, and the torque each commanded when every one of them is a
// haptic playback (else `commanded` stays empty: the design is fitted to the motion).
void read_tobe_recordings(const SpecCommandOptions& options, std::ostream& progress,
                          std::vector<PreparedData>& tobe,
                          std::vector<CommandedTorque>& commanded) {
  bool all_commanded = true;
  for (const std::string& path : options.tobe_paths) {
    progress << "preparing " << path << "\n";
    tobe.push_back(load_prepared_data(path));
    std::optional<CommandedTorque> torque;
    if (!options.motion_only && is_hdf5_file(path)) torque = read_commanded_torque(path);
    if (torque) {
      commanded.push_back(std::move(*torque));
    } else {
      all_commanded = false;
    }
  }
  if (!all_commanded) commanded.clear();
}

// ASIS: a parameter file, or a `doorbench fit` folder holding fitted-params.json.
std::filesystem::path asis_parameter_file(const SpecCommandOptions& options) {
  std::filesystem::path asis_file = options.asis_path;
  if (std::filesystem::is_directory(asis_file)) asis_file /= "fitted-params.json";
  if (!std::filesystem::exists(asis_file)) {
    throw std::runtime_error(asis_file.string() +
                             ": no such file (--asis takes a physical "
                             "parameter file or a doorbench fit folder)");
  }
  return asis_file;
}

// The AS-IS door, and the parameter names of --fixed and --costs checked against it before
// the TO-BE recordings are read: exit 2 with the valid ones.
DoorModel load_asis(const SpecCommandOptions& options, const std::filesystem::path& asis_file) {
  DoorModel asis = load_model(ModelKind::kPhysical, asis_file, "");
  check_parameter_names(asis, "--fixed", split_names(options.fixed));
  std::map<std::string, double> costs;
  parse_costs(options.costs, costs);
  for (const auto& [name, cost] : costs) check_parameter_names(asis, "--costs", {name});
  return asis;
}

namespace {

// The inverse design of the TO-BE recordings from `asis`, which is first corrected to its own
// recording on the bench when one is given. Throws StopRequested when `stop` asks.
InverseDesignResult design_stage(const SpecCommandOptions& options, DoorModel& asis,
                                 const std::vector<PreparedData>& tobe,
                                 const std::vector<CommandedTorque>& commanded,
                                 const StopHook& stop, std::ostream& progress) {
  InverseDesignOptions design_options;
  if (options.fixed_given) design_options.fixed = split_names(options.fixed);
  parse_costs(options.costs, design_options.weights);
  design_options.regularization = options.regularization;
  design_options.starts = options.starts;
  if (std::string error = design_options.validate(); !error.empty()) throw UsageError(error);
  const auto design_began = std::chrono::steady_clock::now();
  design_options.progress = [&progress, design_began](const std::string& step) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - design_began).count();
    progress << "  [" << static_cast<int>(seconds) << " s] " << step << "\n" << std::flush;
  };
  design_options.fit.stop_requested = stop;
  if (!options.asis_recording.empty()) {
    asis = asis_on_bench(asis, options.asis_recording, design_options, progress);
  }
  progress << "inverse design: fitting the physical model to " << tobe.size()
           << " TO-BE recording(s), " << design_options.starts << " start(s)\n";
  return inverse_design(asis, tobe, design_options, commanded);
}

// The design's felt quantities, its check against the TO-BE recordings, its tolerances and,
// from a campaign, the panel's tolerances. A stop request during the Monte Carlo leaves the
// tolerances out (SpecEvaluation::interrupted).
SpecEvaluation evaluate_design(const SpecCommandOptions& options, const DoorModel& asis,
                               const InverseDesignResult& design,
                               const std::vector<PreparedData>& tobe,
                               const ToleranceSpec& tolerances,
                               const std::optional<CampaignForSpec>& campaign,
                               const std::string& tobe_source, double felt_share,
                               const StopHook& stop, std::ostream& progress) {
  SpecEvaluationOptions evaluation_options;
  evaluation_options.run_tolerances = !options.no_tolerances;
  evaluation_options.tolerances = tolerances;
  evaluation_options.monte_carlo.samples = options.samples;
  evaluation_options.monte_carlo.threads = options.threads;
  evaluation_options.monte_carlo.seed = options.seed;
  evaluation_options.monte_carlo.stop_requested = stop;
  // The samples' status line, with the time left (app/progress.h).
  StatusLine status(progress, stderr_is_terminal(), 5.0, stderr_terminal_columns());
  evaluation_options.monte_carlo.progress =
      count_progress_display(status, "tolerance Monte Carlo", "samples");
  if (std::string error = evaluation_options.validate(); !error.empty()) throw UsageError(error);
  progress << "felt quantities and the check; tolerance analysis of " << options.samples
           << " samples on "
           << (options.threads > 0 ? options.threads
                                   : static_cast<int>(std::thread::hardware_concurrency()))
           << " thread(s)\n";
  SpecEvaluation evaluation = evaluate_spec(asis, design, tobe, evaluation_options);
  status.finish();
  evaluation.command = describe(options);
  if (campaign && evaluation.tolerances) {
    try {
      evaluation.perceptual =
          perceptual_spec(*campaign, tobe_source, felt_share, design.solutions.front().model,
                          evaluation_options, *evaluation.tolerances, progress);
    } catch (const StopRequested& stopped) {
      evaluation.interrupted = "during " + stopped.where() +
                               " of the panel's tolerances: no "
                               "perceptual tolerance table";
      evaluation.warnings.push_back("interrupted " + evaluation.interrupted);
      return evaluation;
    }
    // The alternatives judged with the panel's JNDs where it measured them.
    EquivalenceOptions equivalence = evaluation_options.equivalence;
    equivalence.felt = evaluation_options.felt;
    equivalence.jnds = evaluation.perceptual->jnds;
    evaluation.equivalence = assess_equivalence(design, equivalence);
    evaluation.equivalence_criterion = equivalence_criterion(equivalence);
  }
  return evaluation;
}

}  // namespace

void run_spec(const SpecCommandOptions& options) {
  if (options.samples < 2) throw UsageError("--samples must be >= 2");
  if (options.threads < 0) throw UsageError("--threads must be >= 0");
  // SIGINT/SIGTERM: the fits end at their next solver iteration, the Monte Carlo at its next
  // sample. Before the design is whole there is nothing to write; after, the specification is
  // written without what the stop cut, marked interrupted. A second signal ends doorbench.
  const StopSignals signals;
  const StopHook stop = [&signals] { return signals.received() != 0; };
  const bool from_campaign = !options.campaign_dir.empty();
  const double felt_share = checked_felt_share(options);
  // The output rule (docs/output-files.md): checked before any work; the folder is made
  // once the inputs are read and the design is done.
  std::vector<std::filesystem::path> inputs(options.tobe_paths.begin(), options.tobe_paths.end());
  inputs.emplace_back(options.asis_path);
  if (!options.asis_recording.empty()) inputs.emplace_back(options.asis_recording);
  if (!options.tolerances_path.empty()) inputs.emplace_back(options.tolerances_path);
  if (from_campaign)
    inputs.push_back(std::filesystem::path(options.campaign_dir) / "analysis.json");
  check_output_folder(options.out_dir, inputs, options.overwrite);
  const auto campaign =
      from_campaign ? std::optional(read_campaign_for_spec(options.campaign_dir)) : std::nullopt;
  const std::filesystem::path asis_file = asis_parameter_file(options);
  DoorModel asis = load_asis(options, asis_file);
  std::ostream& progress = options.show_progress ? std::cerr : null_stream();
  progress << "AS-IS door: " << asis_file.string() << "\n";

  std::vector<PreparedData> tobe;
  std::vector<CommandedTorque> commanded;
  read_tobe_recordings(options, progress, tobe, commanded);
  std::string tobe_source;
  if (campaign) tobe_source = campaign_tobe(*campaign, asis, tobe, progress);
  const std::string bench_warning = bench_without_asis_recording(tobe, !commanded.empty(), options);
  if (!bench_warning.empty()) progress << "warning: " << bench_warning << "\n";
  if (!commanded.empty()) {
    progress << "the TO-BE recordings are haptic playbacks: the design is fitted to the torque "
                "they commanded, the inertia to their motion (--motion-only: the motion alone)\n";
  }
  // Tolerances are read before the long fit, so that a bad file fails at once.
  ToleranceSpec tolerances;
  if (!options.tolerances_path.empty()) {
    tolerances = parse_tolerance_file(read_text_file(options.tolerances_path),
                                      options.tolerances_path, asis);
  }

  if (signals.received() != 0) {
    throw nothing_finished(signals.received(), "spec", "the specification",
                           "the reading of its inputs", options.out_dir);
  }
  std::optional<InverseDesignResult> designed;
  try {
    designed = design_stage(options, asis, tobe, commanded, stop, progress);
  } catch (const StopRequested& stopped) {
    throw nothing_finished(signals.received(), "spec", "the specification", stopped.where(),
                           options.out_dir);
  }
  const InverseDesignResult& design = *designed;
  if (design.solutions.empty()) throw std::runtime_error("inverse design found no solution");

  SpecEvaluation evaluation = evaluate_design(options, asis, design, tobe, tolerances, campaign,
                                              tobe_source, felt_share, stop, progress);
  evaluation.asis_source = asis_file.string();
  if (!bench_warning.empty()) evaluation.warnings.push_back(bench_warning);

  std::filesystem::create_directories(options.out_dir);
  const std::filesystem::path params = std::filesystem::path(options.out_dir) / "tobe-params.json";
  write_text_file_atomically(params, to_parameter_json(design.solutions.front().model));
  // An interrupted specification is written without its PDF (the renderer takes seconds).
  const bool pdf = !options.no_pdf && evaluation.interrupted.empty();
  progress << "writing the specification into " << options.out_dir << "/"
           << (pdf ? " (spec.pdf: weasyprint renders spec.html, a few seconds)" : "") << "\n";
  SpecReportFiles files;
  try {
    files = write_spec_report(options.out_dir, design, evaluation, pdf ? "" : "none", stop);
  } catch (const StopRequested&) {
    throw Interrupted(signals.received(),
                      "spec: " + signal_name(signals.received()) +
                          " stopped the specification during the PDF rendering: no spec.pdf; "
                          "spec.json, spec.html and tobe-params.json in " +
                          options.out_dir + "/ are complete");
  }

  std::cout << design.brief_report() << "\n" << spec_summary(design, evaluation);
  if (evaluation.tolerances) {
    std::cout << "tolerances:\n" << evaluation.tolerances->brief_report();
  }
  if (evaluation.perceptual) {
    std::cout << "tolerances judged by the panel:\n" << evaluation.perceptual->brief_report();
  }
  std::cout << "wrote " << files.json.string() << ", " << files.html.string() << ", "
            << params.string() << "\n"
            << files.pdf_note << "\n";
  if (!evaluation.interrupted.empty()) {
    throw Interrupted(signals.received(), "spec: " + signal_name(signals.received()) +
                                              " stopped the specification " +
                                              evaluation.interrupted + "; the results in " +
                                              options.out_dir + "/ are marked interrupted");
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
