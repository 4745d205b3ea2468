// doorbench campaign report ANALYSIS --out DIR: report.html, report.pdf and every plot again
// from a `campaign analyze` folder's analysis.json, without computing anything (the same
// rendering `campaign analyze` ends with; docs/campaign.md).
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/session/output_file.h"
#include "acquisition/session/pdf_output.h"
#include "analysis/model/parameter_file.h"
#include "app/campaign_report.h"
#include "app/commands.h"
#include "study/statistics/analysis.h"

namespace doorbench::app {

CampaignReportFiles write_campaign_report(const std::filesystem::path& out,
                                          const nlohmann::json& analysis, bool pdf,
                                          std::ostream& progress, const StopHook& stop) {
  CampaignReportFiles files;
  const std::vector<study::AnalysisPlot> plots = study::analysis_plots(analysis);
  std::vector<std::string> drawn;
  for (const study::AnalysisPlot& plot : plots) drawn.push_back(plot.file);
  remove_outputs_not_written(out, study::is_analysis_plot_file, drawn);
  for (const study::AnalysisPlot& plot : plots)
    write_text_file_atomically(out / plot.file, plot.svg);
  files.plots = static_cast<int>(plots.size());
  files.html = out / "report.html";
  write_text_file_atomically(files.html, study::analysis_html(analysis, plots));
  files.pdf_note = "no PDF (not asked for)";
  if (!pdf) {
    remove_output_not_written(out / "report.pdf");
  } else {
    progress << "rendering " << (out / "report.pdf").string() << "\n" << std::flush;
    const std::string problem = render_pdf(files.html, out / "report.pdf", "", stop);
    files.pdf_note =
        problem.empty() ? "wrote " + (out / "report.pdf").string() : "no PDF: " + problem;
  }
  return files;
}

namespace {

struct CampaignReportOptions {
  std::string analysis_dir;  // a `campaign analyze` folder
  std::string out_dir;
  bool overwrite = false;
  bool no_pdf = false;
};

// FOLDER/analysis.json read; UsageError naming the file when it is not there or not an
// analysis (no "input" object: not written by campaign analyze).
nlohmann::json read_analysis(const std::filesystem::path& folder) {
  const std::filesystem::path file = folder / "analysis.json";
  if (!std::filesystem::is_directory(folder))
    throw UsageError(folder.string() +
                     ": no such folder (give a `doorbench campaign analyze` "
                     "output folder)");
  if (!std::filesystem::is_regular_file(file))
    throw UsageError(file.string() +
                     ": no such file (give a `doorbench campaign analyze` "
                     "output folder)");
  nlohmann::json analysis;
  try {
    analysis = nlohmann::json::parse(read_text_file(file));
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error(file.string() + ": not JSON: " + error.what());
  }
  if (!analysis.is_object() || !analysis.contains("input") || !analysis["input"].is_object())
    throw std::runtime_error(file.string() +
                             ": not a campaign analysis (no input object; written by "
                             "`doorbench campaign analyze`?)");
  return analysis;
}

void run_campaign_report(const CampaignReportOptions& options) {
  const std::filesystem::path folder(options.analysis_dir);
  const nlohmann::json analysis = read_analysis(folder);
  const std::filesystem::path out(options.out_dir);
  check_output_folder(out, {folder / "analysis.json"}, options.overwrite);
  std::filesystem::create_directories(out);
  CampaignReportFiles files;
  try {
    files = write_campaign_report(out, analysis, !options.no_pdf, std::cerr);
  } catch (const nlohmann::json::exception& error) {
    throw std::runtime_error((folder / "analysis.json").string() +
                             ": a section lacks what its plot reads: " + error.what());
  }
  std::cout << study::analysis_summary(analysis);
  std::cout << "wrote " << files.html.string() << " and " << files.plots << " plot(s)\n"
            << files.pdf_note << "\n";
}

}  // namespace

void add_campaign_report(CLI::App& campaign, Action& action) {
  auto options = std::make_shared<CampaignReportOptions>();
  CLI::App* command = campaign.add_subcommand(
      "report",
      "The report again from a `campaign analyze` folder, computing nothing: report.html, "
      "report.pdf and the plots (preference scale, psychometric curves with the answers, "
      "ratings, the tuned doors) into --out");
  command->add_option("ANALYSIS", options->analysis_dir, "a `campaign analyze` output folder")
      ->required();
  command->add_option("--out", options->out_dir, "folder for the report")->required();
  command->add_flag("--overwrite", options->overwrite,
                    "write into an --out folder that exists and is not empty");
  command->add_flag("--no-pdf", options->no_pdf, "do not render report.pdf");
  command->callback([options, &action] { action = [options] { run_campaign_report(*options); }; });
}

}  // namespace doorbench::app
