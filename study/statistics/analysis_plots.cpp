// The campaign report's plots, drawn from analysis.json alone (study/statistics/analysis.h,
// analysis_plots): forest plots with the names on the axis for the preference scale,
// identify-real, 2-AC and the ratings; the psychometric curves with the answers; the tuned
// doors.
#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/report/svg_charts.h"
#include "core/number_format.h"
#include "study/statistics/analysis.h"
#include "study/statistics/thresholds.h"
#include "study/statistics/tuning.h"

namespace doorbench::study {
namespace {

// Participants drawn one row each up to this many; beyond, the plot says how many are left
// out (analysis.json and the table have them all).
constexpr std::size_t kMostParticipantRows = 30;
constexpr double kOpen = std::numeric_limits<double>::infinity();

double number_or_nan(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::nan("");
}

void add_forest(std::vector<AnalysisPlot>& plots, const std::string& file,
                const ForestOptions& options, const std::vector<ForestRow>& rows) {
  bool drawable = false;
  for (const ForestRow& row : rows)
    drawable = drawable || std::isfinite(row.estimate) || std::isfinite(row.low) ||
               std::isfinite(row.high);
  if (drawable) plots.push_back({file, options.title, render_svg_forest(options, rows)});
}

// The worths, best first, with their 95 % intervals and the quasi-variance comparison
// intervals.
void add_preference_plot(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  std::vector<nlohmann::json> worths(analysis["preference_scale"].begin(),
                                     analysis["preference_scale"].end());
  std::stable_sort(worths.begin(), worths.end(),
                   [](const nlohmann::json& a, const nlohmann::json& b) {
                     return number_or_nan(a["worth"]) > number_or_nan(b["worth"]);
                   });
  std::vector<ForestRow> rows;
  bool compared = false;
  for (const nlohmann::json& w : worths) {
    ForestRow row;
    const bool reference = w.value("interval", "") == "reference";
    row.label = w["variant"].get<std::string>();
    row.estimate = number_or_nan(w["worth"]);
    if (!reference) {
      row.low = number_or_nan(w["ci_low"]);
      row.high = number_or_nan(w["ci_high"]);
    }
    row.inner_low = number_or_nan(w.value("comparison_low", nlohmann::json()));
    row.inner_high = number_or_nan(w.value("comparison_high", nlohmann::json()));
    compared = compared || std::isfinite(row.inner_low);
    if (reference) row.note = "the reference: worth 0 by definition";
    rows.push_back(row);
  }
  ForestOptions options;
  options.title = "Preference scale: Bradley-Terry worths, best first";
  options.x_label = "worth against the reference (log odds) [-]";
  options.inner_label = "comparison interval";
  if (!compared) options.title += " (no comparison intervals: two variants)";
  add_forest(plots, kPreferencePlotFile, options, rows);
}

ForestRow dprime_row(const std::string& label, const nlohmann::json& r) {
  ForestRow row;
  row.label = label;
  row.estimate = number_or_nan(r["dprime"]);
  row.low = number_or_nan(r["ci_low"]);
  row.high = number_or_nan(r["ci_high"]);
  // JSON has no infinity: an end that is null beside a finite other end is open.
  if (std::isnan(row.high) && std::isfinite(row.low)) row.high = kOpen;
  if (std::isnan(row.low) && std::isfinite(row.high)) row.low = -kOpen;
  return row;
}

void set_margin(ForestOptions& options, const nlohmann::json& section) {
  const double margin = number_or_nan(section.value("equivalence_margin", nlohmann::json()));
  if (!std::isfinite(margin)) return;
  options.band_low = -margin;
  options.band_high = margin;
  options.band_label = "margin |d'| < " + format_significant(margin, 3);
}

void add_identify_plot(const nlohmann::json& ir, std::vector<AnalysisPlot>& plots) {
  std::vector<ForestRow> rows{dprime_row("panel", ir["panel"])};
  rows.front().note = ir["panel"].value("note", "");
  const nlohmann::json& people = ir["participants"];
  for (std::size_t p = 0; p < people.size() && p < kMostParticipantRows; ++p)
    rows.push_back(dprime_row(people[p]["participant"].get<std::string>(), people[p]));
  if (people.size() > kMostParticipantRows) {
    ForestRow more;
    more.label = "...";
    more.note = std::to_string(people.size() - kMostParticipantRows) +
                " more participants: in the table and analysis.json";
    rows.push_back(more);
  }
  ForestOptions options;
  options.title = "Real vs virtual: d' (2-AFC), 95 % intervals";
  options.x_label = "d' (0: chance; > 0: the real door told apart) [-]";
  set_margin(options, ir);
  add_forest(plots, kIdentifyPlotFile, options, rows);
}

void add_two_ac_plot(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  std::vector<ForestRow> rows;
  for (const nlohmann::json& r : analysis["two_ac"]) {
    ForestRow row =
        dprime_row(r["first"].get<std::string>() + " vs " + r["second"].get<std::string>(), r);
    row.note = r.value("note", "");
    rows.push_back(row);
  }
  ForestOptions options;
  options.title = "2-AC: d' per pair (> 0: the second preferred), 95 % intervals";
  options.x_label = "d' (< 0: the first preferred; > 0: the second) [-]";
  if (!analysis["two_ac"].empty()) set_margin(options, analysis["two_ac"].front());
  add_forest(plots, kTwoAcPlotFile, options, rows);
}

void add_ratings_plots(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  for (const auto& model : analysis["ratings_models"]) {
    if (!model.value("converged", false)) continue;  // the table says so; no picture of it
    const std::string attribute = model.at("attribute").get<std::string>();
    std::vector<ForestRow> rows;
    for (const auto& r : analysis["ratings"]) {
      if (r.at("attribute") != attribute) continue;
      ForestRow row;
      const bool reference = r.value("reference", false);
      row.label = r.at("variant").get<std::string>();
      row.estimate = number_or_nan(r["estimate"]);
      if (!reference) {
        row.low = number_or_nan(r["ci_low"]);
        row.high = number_or_nan(r["ci_high"]);
      } else {
        row.note = "the reference: 0 by definition";
      }
      rows.push_back(row);
    }
    ForestOptions options;
    options.title = "Ratings of " + attribute + ": each variant's shift, 95 % intervals";
    options.x_label = "shift on the latent scale against the reference (logit) [-]";
    add_forest(plots, plot_file_name(kRatingsPlotPrefix, attribute), options, rows);
  }
}

// The panel's psychometric curve with its band and the answers per level, from the jnd rows
// and jnd_levels.
void add_psychometric_plots(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  if (!analysis.contains("jnd_levels") || !analysis.contains("jnd")) return;
  for (const nlohmann::json& levels : analysis["jnd_levels"]) {
    ParameterThresholds t;
    t.parameter = levels.at("parameter").get<std::string>();
    t.reference = levels.at("reference").get<std::string>();
    for (const nlohmann::json& c : levels.at("counts"))
      t.counts.push_back({c.at("log_ratio").get<double>(), c.at("trials").get<int>(),
                          c.at("stronger").get<int>()});
    for (const nlohmann::json& c : levels.value("curve", nlohmann::json::array()))
      t.curve.push_back({c.at("log_ratio").get<double>(), c.at("p").get<double>(),
                         c.at("p_low").get<double>(), c.at("p_high").get<double>()});
    bool found = false;
    for (const nlohmann::json& row : analysis["jnd"]) {
      if (row.value("participant", "") != "panel" ||
          row.value("method", "") != "psychometric fit, pooled" ||
          row.value("parameter", "") != t.parameter || row.value("reference", "") != t.reference)
        continue;
      t.panel.shape = levels.value("shape", "") == "weibull" ? PsychometricShape::kWeibull
                                                             : PsychometricShape::kCumulativeNormal;
      t.panel.pse = row.at("pse").get<double>();
      t.panel.spread = row.at("spread").get<double>();
      t.panel.lapse = row.at("lapse").get<double>();
      t.panel.weber_fraction = row.at("weber_fraction").get<double>();
      found = true;
    }
    if (!found || t.counts.empty()) continue;
    plots.push_back({plot_file_name(kJndPlotPrefix, t.parameter),
                     "Psychometric function: " + t.parameter, render_psychometric_plot(t)});
  }
}

// The tuned doors in perceptual steps, from the tuning section.
void add_tuning_plot(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  if (!analysis.contains("tuning")) return;
  const nlohmann::json& tuning = analysis["tuning"];
  TuningResult t;
  for (const nlohmann::json& row : tuning.at("parameters")) {
    ParameterDistribution d;
    d.parameter = row.at("parameter").get<std::string>();
    d.centre = number_or_nan(row.at("centre"));
    if (row.at("weber_fraction").is_number())
      d.weber_fraction = row["weber_fraction"].get<double>();
    if (row.at("spread_steps").is_number()) d.spread_steps = row["spread_steps"].get<double>();
    t.parameters.push_back(d);
  }
  const nlohmann::json& groups = tuning.at("clusters").at("groups");
  t.clusters.split = tuning.at("clusters").at("split").get<bool>();
  for (const nlohmann::json& door : tuning.at("doors")) {
    TunedDoor d{door.at("participant").get<std::string>(), door.value("file", ""), {}};
    for (const ParameterDistribution& p : t.parameters)
      d.parameters.emplace_back(p.parameter, door.at("parameters").contains(p.parameter)
                                                 ? number_or_nan(door["parameters"][p.parameter])
                                                 : std::nan(""));
    int group = 0;
    for (std::size_t g = 0; g < groups.size(); ++g)
      for (const nlohmann::json& member : groups[g].at("participants"))
        if (member == d.participant) group = static_cast<int>(g);
    t.clusters.group.push_back(std::min(group, 1));
    t.doors.push_back(std::move(d));
  }
  try {
    plots.push_back({kTuningPlotFile, "The panel's tuned doors", render_tuning_plot(t)});
  } catch (const std::invalid_argument&) {
    // No parameter has perceptual steps: nothing to draw (the JSON says why).
  }
}

}  // namespace

std::string plot_file_name(const std::string& prefix, const std::string& name) {
  std::string out = prefix;
  for (const char c : name) {
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                       c == '.' || c == '_' || c == '-';
    out += plain ? c : '_';
  }
  return out + ".svg";
}

std::vector<AnalysisPlot> analysis_plots(const nlohmann::json& analysis) {
  std::vector<AnalysisPlot> plots;
  if (analysis.contains("preference_scale")) add_preference_plot(analysis, plots);
  if (analysis.contains("identify_real")) add_identify_plot(analysis["identify_real"], plots);
  if (analysis.contains("two_ac")) add_two_ac_plot(analysis, plots);
  if (analysis.contains("ratings") && analysis.contains("ratings_models"))
    add_ratings_plots(analysis, plots);
  add_psychometric_plots(analysis, plots);
  add_tuning_plot(analysis, plots);
  return plots;
}

bool is_analysis_plot_file(const std::string& file) {
  for (const char* fixed :
       {kPreferencePlotFile, kIdentifyPlotFile, kTwoAcPlotFile, kTuningPlotFile}) {
    if (file == fixed) return true;
  }
  // A named plot: the prefix, then only the characters plot_file_name keeps.
  const bool prefixed = file.starts_with(kRatingsPlotPrefix) || file.starts_with(kJndPlotPrefix);
  return prefixed && file.ends_with(".svg") && plot_file_name("", file) == file + ".svg";
}

}  // namespace doorbench::study
