// doorbench campaign analyze: a campaign's trials.csv (a campaign folder, or the table
// alone, even one written by hand) turned into analysis.json, report.html, report.pdf and
// SVG plots (study/statistics/analysis.h; docs/campaign.md).
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "app/campaign_report.h"
#include "app/commands.h"
#include "app/number_options.h"
#include "app/progress.h"
#include "app/stop_signals.h"
#include "study/campaign_plan.h"
#include "study/question.h"
#include "study/statistics/analysis.h"
#include "study/statistics/variant_files.h"
#include "study/trials_table.h"

namespace doorbench::app {
namespace {

std::filesystem::path trials_path(const std::string& input) {
  const std::filesystem::path path(input);
  if (std::filesystem::is_directory(path)) {
    const std::filesystem::path table = path / "trials.csv";
    if (!std::filesystem::exists(table))
      throw UsageError(input +
                       ": is a folder without trials.csv (give a campaign folder or a "
                       "trials table)");
    return table;
  }
  if (!std::filesystem::exists(path)) throw UsageError(input + ": no such file or folder");
  return path;
}

}  // namespace

void run_campaign_analyze(const CampaignAnalyzeOptions& options, std::ostream& progress_out,
                          bool terminal, std::ostream& out) {
  if (options.bootstrap < 0 || (options.bootstrap > 0 && options.bootstrap < 100))
    throw UsageError("--bootstrap: must be 0 (none) or at least 100 resamples, got " +
                     std::to_string(options.bootstrap));
  const std::filesystem::path table_path = trials_path(options.input);
  const std::filesystem::path folder(options.out_dir);
  check_output_folder(folder, {table_path}, options.overwrite);

  study::AnalysisOptions analysis_options;
  analysis_options.preference.bootstrap_replicates = options.bootstrap;
  analysis_options.preference.seed = options.seed;
  analysis_options.preference.reference = options.reference;
  analysis_options.real_variant = options.real_variant;
  analysis_options.equivalence_dprime = options.equivalence_dprime;
  if (const std::string problem = analysis_options.validate(); !problem.empty())
    throw UsageError(problem);

  const study::TrialsTable table = study::read_trials_table(table_path);
  if (options.reference.empty())
    analysis_options.preference.reference = study::plan_reference_variant(options.input, table);
  progress_out << "analysing " << table_path.string() << ": " << table.rows.size() << " trials\n";
  StatusLine status(progress_out, terminal, 5.0, terminal ? stderr_terminal_columns() : 0);
  std::map<std::string, std::function<void(int, int)>> displays;
  const study::AnalysisProgress progress = [&](const std::string& what, int done, int total) {
    auto at = displays.find(what);
    if (at == displays.end())
      at = displays.emplace(what, count_progress_display(status, what, "resamples")).first;
    at->second(done, total);
  };
  // SIGINT/SIGTERM: the section under way ends at its next resample; the sections before it
  // are written, marked interrupted. A second signal ends doorbench at once.
  const StopSignals signals;
  analysis_options.stop_requested = [&signals] { return signals.received() != 0; };
  nlohmann::json analysis = study::analyze_trials(table, analysis_options, progress);
  status.finish();
  const study::VariantFiles variants = study::variant_parameter_files(table, analysis);

  std::filesystem::create_directories(folder);
  study::write_variant_files(folder, variants);
  write_text_file_atomically(folder / "analysis.json", analysis.dump(2) + "\n");
  // An interrupted analysis is written without its PDF (the renderer takes seconds).
  const bool pdf = !options.no_pdf && !analysis.contains("interrupted");
  CampaignReportFiles report;
  try {
    report =
        write_campaign_report(folder, analysis, pdf, progress_out, analysis_options.stop_requested);
  } catch (const StopRequested&) {
    throw Interrupted(signals.received(),
                      "campaign analyze: " + signal_name(signals.received()) +
                          " stopped the analysis during the PDF rendering: no report.pdf; "
                          "analysis.json, report.html and the plots in " +
                          folder.string() + "/ are complete");
  }
  out << study::analysis_summary(analysis);
  out << "wrote " << (folder / "analysis.json").string() << ", " << report.html.string() << ", "
      << report.plots << " plot(s) and " << variants.files.size() << " variant parameter file(s)\n"
      << report.pdf_note << "\n";
  if (analysis.contains("interrupted")) {
    throw Interrupted(signals.received(),
                      "campaign analyze: " + signal_name(signals.received()) +
                          " stopped the analysis " + analysis["interrupted"].get<std::string>() +
                          "; the results in " + folder.string() + "/ are marked interrupted");
  }
}

void analyze_demo_campaign(const std::filesystem::path& dir,
                           const std::filesystem::path& asis_params, std::ostream& out) {
  CampaignAnalyzeOptions options;
  options.input = (dir / "folder").string();
  options.out_dir = (dir / "analysis").string();
  options.overwrite = true;  // the demo owns its folder
  options.no_pdf = true;
  std::ostringstream ignored, summary;
  run_campaign_analyze(options, ignored, false, summary);
  out << "\nthe panel's statistics (doorbench campaign analyze " << options.input << " --out "
      << options.out_dir << "):\n";
  std::istringstream lines(summary.str());
  for (std::string line; std::getline(lines, line);) out << "  " << line << "\n";
  out << "  the specification on the panel's perception (the favourite variant as the TO-BE "
         "feel, tolerances judged by the panel's JNDs; under a minute on two cores):\n"
      << "    doorbench spec --campaign " << options.out_dir << " --asis " << asis_params.string()
      << " --out " << (dir / "spec").string() << " --felt-share 5%\n";
}

void add_campaign_analyze(CLI::App& campaign, Action& action) {
  auto options = std::make_shared<CampaignAnalyzeOptions>();
  CLI::App* command = campaign.add_subcommand(
      "analyze",
      "The panel's statistics from trials.csv: preference scale (Bradley-Terry with ties and "
      "order effect, quasi-variances), real vs virtual (2-AFC d' with equivalence), 2-AC d', "
      "ratings, thresholds, tuned doors (analysis.json, report.html, report.pdf, plots, the "
      "variants' parameter files)");
  command->add_option("INPUT", options->input, "a campaign folder or a trials.csv")->required();
  command->add_option("--out", options->out_dir, "folder for the analysis")->required();
  command->add_flag("--overwrite", options->overwrite,
                    "write into an --out folder that exists and is not empty");
  command
      ->add_option("--bootstrap", options->bootstrap,
                   "participant bootstrap resamples for the preference scale (0: none)")
      ->capture_default_str()
      ->check(number_range(0, 1000000));
  command->add_option("--seed", options->seed, "the bootstrap's seed")->capture_default_str();
  command->add_option(
      "--reference", options->reference,
      "the variant at worth 0 (default: a campaign folder's first variant, else the first in "
      "the table)");
  command
      ->add_option("--real-variant", options->real_variant,
                   "the real door's name in identify-real trials")
      ->capture_default_str();
  command
      ->add_option("--equivalence-dprime", options->equivalence_dprime,
                   "the equivalence margin on d' of identify-real and 2-AC: the doors are called "
                   "indistinguishable only when the 95 % interval of d' lies within +-MARGIN "
                   "(two one-sided tests; 1 is about the 2-AFC JND, docs/campaign.md)")
      ->capture_default_str();
  command->add_flag("--no-pdf", options->no_pdf, "do not render report.pdf");
  command->callback([options, &action] {
    action = [options] {
      run_campaign_analyze(*options, std::cerr, stderr_is_terminal(), std::cout);
    };
  });
}

}  // namespace doorbench::app
