// specify(): the specification's stages in order (specify.h).
#include "analysis/design/specify.h"

#include <chrono>
#include <thread>

#include "acquisition/session/output_file.h"
#include "analysis/design/equivalent_solutions.h"
#include "analysis/design/perceptual_tolerance.h"
#include "analysis/design/tolerance_analysis.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/model/parameter_file.h"
#include "analysis/preprocessing/recording_file.h"
#include "analysis/simulation/fit_synthetic.h"
#include "core/number_format.h"

namespace doorbench {
namespace {

void spec_say(const SpecOptions& options, const std::string& line) {
  if (options.progress) options.progress(line);
}

// The AS-IS door as the bench sees it: `asis` corrected to its own recording by the sparse
// search (docs/inverse-design.md, "The AS-IS door as the bench sees it").
DoorModel asis_on_bench(const DoorModel& asis, const SpecOptions& spec,
                        const InverseDesignOptions& design_options) {
  spec_say(spec, "AS-IS recording: " + spec.asis_recording.string());
  InverseDesignOptions options = design_options;
  options.smallest_change_alongside = false;
  const InverseDesignResult bench =
      inverse_design(asis, {load_prepared_data(spec.asis_recording.string())}, options);
  const DesignSolution& door = bench.solutions.front();
  std::string changes;
  for (const DesignParameter& p : door.parameters) {
    if (p.changed) {
      changes += " " + p.name + " " + format_number(p.as_is) + " -> " + format_number(p.to_be);
    }
  }
  spec_say(spec,
           "the AS-IS door as this bench sees it:" + (changes.empty() ? " as its file" : changes));
  return door.model;
}

// The warning for TO-BE recordings of a real door measured through a bench's sensors (the
// angle integrated from its gyroscope) without an AS-IS recording: the AS-IS parameter file
// is then compared with what the bench measured, and the bench's own deviations can come
// out as design changes (docs/inverse-design.md, "The AS-IS door as the bench sees it").
// "" when the recordings are haptic playbacks, not from a bench, or an AS-IS recording is
// given.
std::string bench_without_asis_recording(const std::vector<PreparedData>& tobe, bool playbacks,
                                         const SpecOptions& options) {
  if (playbacks || !options.asis_recording.empty()) return "";
  std::string paths, how;
  for (std::size_t i = 0; i < tobe.size() && i < options.tobe_paths.size(); ++i) {
    if (tobe[i].angle_source.rfind("rate_rad_s integrated", 0) != 0) continue;
    paths += (paths.empty() ? "" : ", ") + options.tobe_paths[i].string();
    if (how.empty()) how = tobe[i].angle_source;
  }
  if (paths.empty()) return "";
  return "the TO-BE recording " + paths + " was measured through a bench's sensors (angle: " + how +
         ") and --asis-recording is not given: the AS-IS parameter file is compared with what "
         "the bench measured, so the bench's own deviations (sensor offsets and scales, the "
         "load cell's mounting, its friction) can be specified as design changes; record the "
         "AS-IS door on the same bench and give it as --asis-recording";
}

// The TO-BE feel with a campaign: without TO-BE recordings, the panel's door (the favourite
// variant or the tuned doors' centre) opened and closed by the virtual hand, as synthetic
// strokes with the bench's noise (fit_synthetic.h) appended to `tobe`. Returns what the
// report says of it.
std::string campaign_tobe(const SpecOptions& options, const CampaignForSpec& campaign,
                          const DoorModel& asis, std::vector<PreparedData>& tobe) {
  for (const std::string& note : campaign.notes) spec_say(options, "campaign: " + note);
  if (!tobe.empty()) {
    return "the TO-BE recordings given; the campaign gives the JNDs and the panel's results";
  }
  std::string source;
  const DoorModel door = campaign_tobe_model(campaign, asis, source);
  spec_say(options, "TO-BE feel from the panel: " + source);
  PreparedData strokes = synthetic_strokes(door, {});
  strokes.source = "the panel's door (simulated strokes): " + campaign.analysis_path.string();
  tobe.push_back(std::move(strokes));
  return source;
}

// The TO-BE recordings, prepared, and the torque each commanded when every one of them is a
// haptic playback (else `commanded` stays empty: the design is fitted to the motion).
void read_tobe_recordings(const SpecOptions& options, std::vector<PreparedData>& tobe,
                          std::vector<CommandedTorque>& commanded) {
  bool all_commanded = true;
  for (const std::filesystem::path& path : options.tobe_paths) {
    spec_say(options, "preparing " + path.string());
    tobe.push_back(load_prepared_data(path.string()));
    std::optional<CommandedTorque> torque;
    if (!options.motion_only && is_hdf5_file(path.string())) torque = read_commanded_torque(path);
    if (torque) {
      commanded.push_back(std::move(*torque));
    } else {
      all_commanded = false;
    }
  }
  if (!all_commanded) commanded.clear();
}

// ASIS: a parameter file, or a `doorbench fit` folder holding fitted-params.json.
std::filesystem::path asis_parameter_file(const SpecOptions& options) {
  std::filesystem::path asis_file = options.asis_path;
  if (std::filesystem::is_directory(asis_file)) asis_file /= "fitted-params.json";
  if (!std::filesystem::exists(asis_file)) {
    throw std::runtime_error(asis_file.string() +
                             ": no such file (--asis takes a physical "
                             "parameter file or a doorbench fit folder)");
  }
  return asis_file;
}

// The AS-IS door, with the names of `fixed` and `costs` checked against it before the TO-BE
// recordings are read.
DoorModel load_asis(const SpecOptions& options, const std::filesystem::path& asis_file) {
  DoorModel asis = load_model(ModelKind::kPhysical, asis_file, "");
  std::string problem = unknown_parameter_problem(
      asis, "--fixed", options.fixed.value_or(std::vector<std::string>{}));
  for (const auto& [name, cost] : options.costs) {
    if (problem.empty()) problem = unknown_parameter_problem(asis, "--costs", {name});
  }
  if (!problem.empty()) throw SpecOptionsError(problem);
  return asis;
}

// The inverse design of the TO-BE recordings from `asis`, which is first corrected to its own
// recording on the bench when one is given. With a campaign the sparse search's goal is the
// feel: every felt quantity within the panel's JND (typical where it measured none). Throws
// StopRequested when asked to stop.
InverseDesignResult design_stage(const SpecOptions& options, DoorModel& asis,
                                 const std::vector<PreparedData>& tobe,
                                 const std::vector<CommandedTorque>& commanded,
                                 const std::optional<CampaignForSpec>& campaign) {
  InverseDesignOptions design_options;
  if (options.fixed) design_options.fixed = *options.fixed;
  for (const auto& [name, cost] : options.costs) design_options.weights[name] = cost;
  design_options.regularization = options.regularization;
  design_options.starts = options.starts;
  if (std::string error = design_options.validate(); !error.empty()) {
    throw SpecOptionsError(error);
  }
  const auto design_began = std::chrono::steady_clock::now();
  design_options.progress = [&options, design_began](const std::string& step) {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - design_began).count();
    spec_say(options, "  [" + std::to_string(static_cast<int>(seconds)) + " s] " + step);
  };
  design_options.fit.stop_requested = options.stop_requested;
  if (campaign) design_options.felt_jnds = campaign->jnds;
  if (!options.asis_recording.empty()) asis = asis_on_bench(asis, options, design_options);
  spec_say(options, "inverse design: fitting the physical model to " + std::to_string(tobe.size()) +
                        " TO-BE recording(s), " + std::to_string(design_options.starts) +
                        " start(s)");
  return inverse_design(asis, tobe, design_options, commanded);
}

// The panel's side of the specification: the shares felt as different at the tolerances
// the Monte Carlo used, and the proposal keeping them under the level.
PerceptualSpec perceptual_spec(const SpecOptions& spec, const CampaignForSpec& campaign,
                               const std::string& tobe_source, const DoorModel& design,
                               const std::vector<FeltMiss>& misses,
                               const SpecEvaluationOptions& evaluation_options,
                               const ToleranceResult& given) {
  PerceptualSpec p;
  p.campaign = campaign.analysis_path.string();
  p.tobe_source = tobe_source;
  p.notes = campaign.notes;
  if (!misses.empty()) {
    std::string names;
    for (const FeltMiss& miss : misses) names += (names.empty() ? "" : ", ") + miss.quantity;
    p.notes.push_back(
        "the tolerances are around the design, which the panel would feel as "
        "different from the TO-BE in " +
        names + " (the warnings say by how much)");
  }
  p.preference = campaign.preference;
  p.thresholds = campaign.thresholds;
  p.jnds = campaign.jnds;
  p.rows = perceptual_shares(given, p.jnds);
  PerceptualToleranceOptions options;
  options.felt_share = spec.felt_share;
  options.progress = [&spec](double factor, double worst, int samples) {
    spec_say(spec, "  tolerances x " + format_significant(factor, 3) +
                       ": largest share felt as different " + format_significant(100 * worst, 3) +
                       "% (" + std::to_string(samples) + " samples)");
  };
  MonteCarloOptions monte_carlo = evaluation_options.monte_carlo;
  monte_carlo.felt = evaluation_options.felt;
  monte_carlo.progress = nullptr;
  spec_say(spec,
           "perceptual tolerances: the common factor on every tolerance keeping each share "
           "felt as different under " +
               format_significant(100 * spec.felt_share, 3) + "% (a Monte Carlo of up to " +
               std::to_string(monte_carlo.samples) + " samples per factor tried, in batches of " +
               std::to_string(options.batch_samples) +
               " until every share's 99% interval is clear of the level)");
  const ToleranceSpec tolerances{given.tolerances};
  p.proposal =
      propose_perceptual_tolerances(design, tolerances, monte_carlo, p.jnds, options, &given);
  spec_say(spec, "  " + p.proposal.summary);
  return p;
}

// The panel's tolerances and the alternatives judged with its JNDs, added to `evaluation`;
// a stop request leaves them out (SpecEvaluation::interrupted).
void add_panel(const SpecOptions& options, const CampaignForSpec& campaign,
               const InverseDesignResult& design, const std::string& tobe_source,
               const SpecEvaluationOptions& evaluation_options, SpecEvaluation& evaluation) {
  try {
    evaluation.perceptual =
        perceptual_spec(options, campaign, tobe_source, design.solutions.front().model,
                        design.felt_misses, evaluation_options, *evaluation.tolerances);
  } catch (const StopRequested& stopped) {
    evaluation.interrupted = "during " + stopped.where() +
                             " of the panel's tolerances: no "
                             "perceptual tolerance table";
    evaluation.warnings.push_back("interrupted " + evaluation.interrupted);
    return;
  }
  EquivalenceOptions equivalence = evaluation_options.equivalence;
  equivalence.felt = evaluation_options.felt;
  equivalence.jnds = evaluation.perceptual->jnds;
  evaluation.equivalence = assess_equivalence(design, equivalence);
  evaluation.equivalence_criterion = equivalence_criterion(equivalence);
}

// The design's felt quantities, its check against the TO-BE recordings, its tolerances and,
// from a campaign, the panel's tolerances. A stop request during the Monte Carlo leaves the
// tolerances out (SpecEvaluation::interrupted).
SpecEvaluation evaluate_design(const SpecOptions& options, const DoorModel& asis,
                               const InverseDesignResult& design,
                               const std::vector<PreparedData>& tobe,
                               const ToleranceSpec& tolerances,
                               const std::optional<CampaignForSpec>& campaign,
                               const std::string& tobe_source) {
  SpecEvaluationOptions evaluation_options;
  evaluation_options.run_tolerances = options.tolerances;
  evaluation_options.tolerances = tolerances;
  evaluation_options.monte_carlo.samples = options.samples;
  evaluation_options.monte_carlo.threads = options.threads;
  evaluation_options.monte_carlo.seed = options.seed;
  evaluation_options.monte_carlo.stop_requested = options.stop_requested;
  evaluation_options.monte_carlo.progress = options.monte_carlo_progress;
  if (std::string error = evaluation_options.validate(); !error.empty()) {
    throw SpecOptionsError(error);
  }
  const int threads =
      options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  spec_say(options, "felt quantities and the check; tolerance analysis of " +
                        std::to_string(options.samples) + " samples on " + std::to_string(threads) +
                        " thread(s)");
  SpecEvaluation evaluation = evaluate_spec(asis, design, tobe, evaluation_options);
  evaluation.command = options.command;
  if (campaign && evaluation.tolerances) {
    add_panel(options, *campaign, design, tobe_source, evaluation_options, evaluation);
  }
  return evaluation;
}

// The output rule (docs/output-files.md), before any work.
void check_out_dir(const SpecOptions& options) {
  std::vector<std::filesystem::path> inputs(options.tobe_paths.begin(), options.tobe_paths.end());
  inputs.push_back(options.asis_path);
  if (!options.asis_recording.empty()) inputs.push_back(options.asis_recording);
  if (!options.tolerances_path.empty()) inputs.push_back(options.tolerances_path);
  if (!options.campaign_dir.empty()) inputs.push_back(options.campaign_dir / "analysis.json");
  check_output_folder(options.out_dir, inputs, options.overwrite);
}

// spec.json, spec.html (spec.pdf) and tobe-params.json into the output folder.
void write_outputs(const SpecOptions& options, SpecSummary& summary) {
  std::filesystem::create_directories(options.out_dir);
  summary.params_file = options.out_dir / "tobe-params.json";
  write_text_file_atomically(summary.params_file,
                             to_parameter_json(summary.design.solutions.front().model));
  // An interrupted specification is written without its PDF (the renderer takes seconds).
  const bool pdf = options.pdf && summary.evaluation.interrupted.empty();
  spec_say(options, "writing the specification into " + options.out_dir.string() + "/" +
                        (pdf ? " (spec.pdf: weasyprint renders spec.html, a few seconds)" : ""));
  try {
    summary.files = write_spec_report(options.out_dir, summary.design, summary.evaluation,
                                      pdf ? "" : "none", options.stop_requested);
  } catch (const StopRequested&) {
    summary.pdf_interrupted = true;
  }
}

}  // namespace

std::string SpecOptions::validate() const {
  if (samples < 2) return "--samples must be >= 2";
  if (threads < 0) return "--threads must be >= 0";
  const bool from_campaign = !campaign_dir.empty();
  if (tobe_paths.empty() && !from_campaign)
    return "spec: give TO-BE recordings or --campaign FOLDER";
  if (from_campaign && !tolerances) {
    return "--campaign needs the tolerance analysis: drop --no-tolerances";
  }
  if (!(felt_share > 0 && felt_share < 1)) return "--felt-share must be between 0 and 1";
  if (from_campaign && !read_campaign) return "a campaign needs its reader (read_campaign)";
  return "";
}

SpecSummary specify(const SpecOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) throw SpecOptionsError(problem);
  check_out_dir(options);
  const std::optional<CampaignForSpec> campaign =
      options.campaign_dir.empty() ? std::nullopt
                                   : std::optional(options.read_campaign(options.campaign_dir));
  SpecSummary summary;
  summary.asis_file = asis_parameter_file(options);
  DoorModel asis = load_asis(options, summary.asis_file);
  spec_say(options, "AS-IS door: " + summary.asis_file.string());

  std::vector<PreparedData> tobe;
  std::vector<CommandedTorque> commanded;
  read_tobe_recordings(options, tobe, commanded);
  std::string tobe_source;
  if (campaign) tobe_source = campaign_tobe(options, *campaign, asis, tobe);
  const std::string bench_warning = bench_without_asis_recording(tobe, !commanded.empty(), options);
  if (!bench_warning.empty()) spec_say(options, "warning: " + bench_warning);
  if (!commanded.empty()) {
    spec_say(options,
             "the TO-BE recordings are haptic playbacks: the design is fitted to the torque "
             "they commanded, the inertia to their motion (--motion-only: the motion alone)");
  }
  // Tolerances are read before the long fit, so that a bad file fails at once.
  ToleranceSpec tolerances;
  if (!options.tolerances_path.empty()) {
    tolerances = parse_tolerance_file(read_text_file(options.tolerances_path),
                                      options.tolerances_path.string(), asis);
  }
  if (stop_requested(options.stop_requested)) throw StopRequested("the reading of its inputs");
  summary.design = design_stage(options, asis, tobe, commanded, campaign);
  if (summary.design.solutions.empty())
    throw std::runtime_error("inverse design found no solution");
  for (const std::string& warning : summary.design.felt_miss_warnings()) {
    spec_say(options, "warning: " + warning);
  }

  summary.evaluation =
      evaluate_design(options, asis, summary.design, tobe, tolerances, campaign, tobe_source);
  summary.evaluation.asis_source = summary.asis_file.string();
  if (!bench_warning.empty()) summary.evaluation.warnings.push_back(bench_warning);
  write_outputs(options, summary);
  return summary;
}

std::string SpecSummary::brief_report() const {
  std::string text = design.brief_report() + "\n" + spec_summary(design, evaluation);
  if (evaluation.tolerances) text += "tolerances:\n" + evaluation.tolerances->brief_report();
  if (evaluation.perceptual) {
    text += "tolerances judged by the panel:\n" + evaluation.perceptual->brief_report();
  }
  return text + "wrote " + files.json.string() + ", " + files.html.string() + ", " +
         params_file.string() + "\n" + files.pdf_note + "\n";
}

}  // namespace doorbench
