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
#include "analysis/design/inverse_design.h"
#include "analysis/design/spec_report.h"
#include "analysis/design/tolerance_analysis.h"
#include "analysis/fit/commanded_torque.h"
#include "analysis/model/parameter_file.h"
#include "app/commands.h"
#include "app/fit_inputs.h"
#include "app/progress.h"
#include "app/spec_run.h"
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

std::string describe(const SpecCommandOptions& o) {
  std::string text = "doorbench spec";
  for (const std::string& path : o.tobe_paths) text += " " + path;
  text += " --asis " + o.asis_path + " --out " + o.out_dir;
  if (!o.asis_recording.empty()) text += " --asis-recording " + o.asis_recording;
  if (o.fixed_given) text += " --fixed " + (o.fixed.empty() ? std::string("''") : o.fixed);
  if (!o.costs.empty()) text += " --costs " + o.costs;
  if (!o.tolerances_path.empty()) text += " --tolerances " + o.tolerances_path;
  text += " --samples " + std::to_string(o.samples) + " --seed " + std::to_string(o.seed);
  return text;
}

}  // namespace

void run_spec(const SpecCommandOptions& options) {
  if (options.samples < 2) throw UsageError("--samples must be >= 2");
  if (options.threads < 0) throw UsageError("--threads must be >= 0");
  // The output rule (docs/output-files.md): checked before any work; the folder is made
  // once the inputs are read and the design is done.
  std::vector<std::filesystem::path> inputs(options.tobe_paths.begin(), options.tobe_paths.end());
  inputs.emplace_back(options.asis_path);
  if (!options.asis_recording.empty()) inputs.emplace_back(options.asis_recording);
  if (!options.tolerances_path.empty()) inputs.emplace_back(options.tolerances_path);
  check_output_folder(options.out_dir, inputs, options.overwrite);
  // ASIS: a parameter file, or a `doorbench fit` folder holding fitted-params.json.
  std::filesystem::path asis_file = options.asis_path;
  if (std::filesystem::is_directory(asis_file)) asis_file /= "fitted-params.json";
  if (!std::filesystem::exists(asis_file)) {
    throw std::runtime_error(asis_file.string() +
                             ": no such file (--asis takes a physical "
                             "parameter file or a doorbench fit folder)");
  }
  DoorModel asis = load_model(ModelKind::kPhysical, asis_file, "");
  std::ostream& progress = options.show_progress ? std::cerr : null_stream();
  progress << "AS-IS door: " << asis_file.string() << "\n";

  std::vector<PreparedData> tobe;
  std::vector<CommandedTorque> commanded;
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
  if (!options.asis_recording.empty()) {
    asis = asis_on_bench(asis, options.asis_recording, design_options, progress);
  }
  progress << "inverse design: fitting the physical model to " << tobe.size()
           << " TO-BE recording(s), " << design_options.starts << " start(s)\n";
  const InverseDesignResult design = inverse_design(asis, tobe, design_options, commanded);
  if (design.solutions.empty()) throw std::runtime_error("inverse design found no solution");

  SpecEvaluationOptions evaluation_options;
  evaluation_options.run_tolerances = !options.no_tolerances;
  evaluation_options.tolerances = tolerances;
  evaluation_options.monte_carlo.samples = options.samples;
  evaluation_options.monte_carlo.threads = options.threads;
  evaluation_options.monte_carlo.seed = options.seed;
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
  evaluation.asis_source = asis_file.string();

  std::filesystem::create_directories(options.out_dir);
  const SpecReportFiles files =
      write_spec_report(options.out_dir, design, evaluation, options.no_pdf ? "none" : "");
  const std::filesystem::path params = std::filesystem::path(options.out_dir) / "tobe-params.json";
  write_text_file_atomically(params, to_parameter_json(design.solutions.front().model));

  std::cout << design.brief_report() << "\n" << spec_summary(design, evaluation);
  if (evaluation.tolerances) {
    std::cout << "tolerances:\n" << evaluation.tolerances->brief_report();
  }
  std::cout << "wrote " << files.json.string() << ", " << files.html.string() << ", "
            << params.string() << "\n"
            << files.pdf_note << "\n";
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
                   "TO-BE recordings (sessions or CSV), e.g. haptic playback sessions")
      ->required()
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
  // Either would be ignored with --no-tolerances (issue 33).
  CLI::Option* samples = command->get_option("--samples");
  command->add_flag("--no-tolerances", options->no_tolerances, "skip the tolerance analysis")
      ->excludes(tolerances)
      ->excludes(samples);
  command->callback([options, &action] { action = [options] { run_spec(*options); }; });
}

}  // namespace doorbench::app
