#pragma once
// The campaign report (docs/campaign.md, "The report"): report.html, report.pdf and every
// plot drawn from an analysis.json alone (study/statistics/analysis.h analysis_plots), written
// by `campaign analyze` after it computes and by `campaign report ANALYSIS --out DIR` from an
// existing analysis folder. `analyze_demo_campaign` is the demo's step.
//
// Errors: OutputError from the writers; render_pdf's problem is returned, not thrown, and its
// StopRequested passed on.
// Thread safety: writes files; one call at a time per folder.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>

#include "core/stop_request.h"
#include "study/statistics/discrimination.h"

namespace doorbench::app {

// `campaign analyze`'s options (app/campaign_analyze_command.cpp).
struct CampaignAnalyzeOptions {
  std::string input;  // a campaign folder (its trials.csv) or a trials table
  std::string out_dir;
  bool overwrite = false;
  bool no_pdf = false;
  int bootstrap = 1000;
  std::uint64_t seed = 1;
  std::string reference;
  std::string real_variant = "real";
  double equivalence_dprime = study::kDefaultEquivalenceDprime;  // identify-real, 2-AC
};

// The verb: analysis.json, the variants' parameter files and the report into out_dir.
// Progress (the trials read, the bootstrap's status line; `terminal`: redrawn in place) on
// `progress`, the summary and the files written on `out`. Throws UsageError for bad options
// or input, OutputRefused by the output rule, TrialsTableError and the sections' errors.
void run_campaign_analyze(const CampaignAnalyzeOptions& options, std::ostream& progress,
                          bool terminal, std::ostream& out);

struct CampaignReportFiles {
  std::filesystem::path html;
  int plots = 0;
  std::string pdf_note;  // "wrote OUT/report.pdf", "no PDF (not asked for)" or "no PDF: why"
};

// Writes the plots, report.html and (when `pdf`) report.pdf into `out`, which must exist. An
// earlier run's plot (a name study::is_analysis_plot_file knows) that this analysis does not
// draw, and its report.pdf when this run renders none, are removed (output rule 5); other
// files are left alone. The rest of the output rule (check_output_folder) is the caller's.
// `progress` gets a line before the PDF. Throws StopRequested when `stop` asked during the PDF's
// rendering (no PDF then).
CampaignReportFiles write_campaign_report(const std::filesystem::path& out,
                                          const nlohmann::json& analysis, bool pdf,
                                          std::ostream& progress, const StopHook& stop = {});

// The demo's step after its simulated campaign: `campaign analyze` of dir/folder into
// dir/analysis (no PDF, no bootstrap: two participants), a line per result on `out`, and the
// `spec --campaign` command that builds the specification on it.
void analyze_demo_campaign(const std::filesystem::path& dir,
                           const std::filesystem::path& asis_params, std::ostream& out);

}  // namespace doorbench::app
