#pragma once
// `doorbench campaign analyze`: a campaign's trials table turned into analysis.json, a
// report (report.html, report.pdf) and SVG plots (docs/campaign.md).
//
// analysis.json is one object. Its keys come from sections: each section is a function of
// the trials table that returns a JSON object whose keys are merged into analysis.json, or
// null when the table has no trials of its kind. Sections today (analysis_sections()):
//   "preference"      -> preference_scale, ties (when `same` answers exist), order_effect
//                        (when some pair came in both orders), preference_fit
//   "identify_real"   -> identify_real
//   "two_ac"          -> two_ac
//   "ratings"         -> ratings, ratings_models   (study/statistics/ratings.h)
//   "jnd"             -> jnd, jnd_levels (the pooled answers per comparison level), plus a
//                        psychometric plot per parameter (thresholds.h)
//   "tuning"          -> tuning, plus its plot; tune rows' files are read relative to the
//                        trials table's folder; measured Weber fractions from "jnd" (tuning.h)
// plus "input" (the table's path, row and participant counts) and "sections" (each
// section's name and whether it found data, or its error). A section that fails on its data
// (separation, an error in the table) stops the analysis with that error: the table is
// wrong or cannot give an answer, and a report that leaves a part out silently would mislead.
//
// Errors: TrialsTableError from the table's rows (naming the line), PreferenceScaleError,
// OutputError from the writers.
// Thread safety: free functions without shared state; `progress` on the caller's thread.
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/stop_request.h"
#include "study/statistics/discrimination.h"
#include "study/statistics/preference_scale.h"
#include "study/trials_table.h"

namespace doorbench::study {

struct AnalysisOptions {
  PreferenceOptions preference;
  std::string real_variant = "real";  // the real door's name in identify-real trials
  double confidence = 0.95;
  // Asked between sections and within the long ones (core/stop_request.h): when it returns
  // true the section under way is abandoned and analysis.json's "interrupted" says which;
  // the sections before it are kept. Also the preference bootstrap's when that has none.
  StopHook stop_requested;
  // identify-real's and 2-AC's equivalence margin on d' (--equivalence-dprime)
  double equivalence_dprime = kDefaultEquivalenceDprime;
  std::string validate() const;  // empty when usable
};

// Progress of a long section: what, done, total (a stage begins at done == 0).
using AnalysisProgress = std::function<void(const std::string& what, int done, int total)>;

// The plots of an analysis: file name (e.g. "preference-scale.svg") and SVG text.
struct AnalysisPlot {
  std::string file;
  std::string title;
  std::string svg;
};

// One section of analysis.json.
struct AnalysisSection {
  std::string name;
  std::function<nlohmann::json(const TrialsTable&)> make;  // object of keys, or null
  // Plots that need more than the JSON (called after make; may be empty).
  std::function<std::vector<AnalysisPlot>()> plots;
};

// The sections, in report order, made with `options` and reporting to `progress`.
std::vector<AnalysisSection> analysis_sections(const AnalysisOptions& options,
                                               const AnalysisProgress& progress = {});

// analysis.json's object from the table (every section of analysis_sections()) and, in
// `section_plots` when given, the plots the sections drew from their fits (psychometric
// curves, tuned doors). analysis_plots draws the same from the JSON alone, which is what the
// verbs write (tests/study/test_campaign_report.cpp checks that the two agree).
nlohmann::json analyze_trials(const TrialsTable& table, const AnalysisOptions& options = {},
                              const AnalysisProgress& progress = {},
                              std::vector<AnalysisPlot>* section_plots = nullptr);

// Every plot, drawn from analysis.json alone (what `campaign analyze` and `campaign report`
// write; study/statistics/analysis_plots.cpp): forest plots with the names on the axis,
// preference-scale.svg (the worths best first, their 95 % intervals and quasi-variance
// comparison intervals), identify-real.svg (the panel and up to 30 participants, the
// equivalence margin shaded), two-ac.svg (one row per pair) and ratings-ATTRIBUTE.svg (for
// each converged ratings model); jnd-PARAMETER.svg (the panel's psychometric curve with its
// 95 % band, the pooled answers as points sized by their trials, from jnd_levels) and
// tuning.svg (the tuned doors in perceptual steps). Throws nlohmann::json::exception for a
// section without the fields these plots read.
std::vector<AnalysisPlot> analysis_plots(const nlohmann::json& analysis);

// The plots' file names: fixed for the preference scale, identify-real, 2-AC and the tuned
// doors; a prefix and the attribute or parameter for the ratings and the psychometric curves.
inline constexpr const char* kPreferencePlotFile = "preference-scale.svg";
inline constexpr const char* kIdentifyPlotFile = "identify-real.svg";
inline constexpr const char* kTwoAcPlotFile = "two-ac.svg";
inline constexpr const char* kTuningPlotFile = "tuning.svg";
inline constexpr const char* kRatingsPlotPrefix = "ratings-";
inline constexpr const char* kJndPlotPrefix = "jnd-";

// A plot's file: PREFIX + NAME with every character outside [A-Za-z0-9._-] as '_' + ".svg"
// ("ratings-" and "heavy/light" give "ratings-heavy_light.svg").
std::string plot_file_name(const std::string& prefix, const std::string& name);

// Whether `file` (a name, no folder) is one analysis_plots can give: preference-scale.svg,
// identify-real.svg, two-ac.svg, tuning.svg, or "ratings-" or "jnd-" + NAME + ".svg". The
// report removes such a file of an earlier run that this analysis does not draw.
bool is_analysis_plot_file(const std::string& file);

// report.html (study/statistics/analysis_html.cpp): every key of the analysis as a section
// (the known ones as tables with the model's words, numbers to the digits a reader needs and
// p-values as "< 0.001" or 3 significant digits, no number or name broken across lines; any
// other key as a generic table), the plots inline.
std::string analysis_html(const nlohmann::json& analysis, const std::vector<AnalysisPlot>& plots);

// The summary printed by the verb: one line per section.
std::string analysis_summary(const nlohmann::json& analysis);

}  // namespace doorbench::study
