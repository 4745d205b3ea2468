#include "study/statistics/analysis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <set>

#include "acquisition/session/output_file.h"
#include "analysis/report/svg_plot.h"
#include "core/number_format.h"
#include "study/statistics/discrimination.h"
#include "study/statistics/ratings.h"
#include "study/statistics/thresholds.h"
#include "study/statistics/tuning.h"

namespace doorbench::study {

std::string AnalysisOptions::validate() const {
  if (const std::string problem = preference.validate(); !problem.empty()) return problem;
  if (!(confidence > 0.5 && confidence < 1)) return "confidence must be in (0.5, 1)";
  if (!(equivalence_dprime > 0) || !std::isfinite(equivalence_dprime))
    return "the equivalence margin must be a positive d'";
  if (real_variant.empty()) return "the real door's variant name must not be empty";
  return "";
}

namespace {

// The pooled counts per comparison level behind each panel fit (what the psychometric plot
// draws as data; `campaign report` redraws it from analysis.json alone).
nlohmann::json jnd_levels_json(const ThresholdsResult& thresholds) {
  nlohmann::json rows = nlohmann::json::array();
  for (const ParameterThresholds& p : thresholds.parameters) {
    nlohmann::json counts = nlohmann::json::array();
    for (const LevelCount& c : p.counts)
      counts.push_back({{"ratio", std::exp(c.level)},
                        {"log_ratio", c.level},
                        {"trials", c.trials},
                        {"stronger", c.stronger}});
    nlohmann::json curve = nlohmann::json::array();
    for (const CurvePoint& c : p.curve)
      curve.push_back({{"ratio", std::exp(c.level)},
                       {"log_ratio", c.level},
                       {"p", c.p},
                       {"p_low", c.low},
                       {"p_high", c.high}});
    rows.push_back(
        {{"parameter", p.parameter},
         {"reference", p.reference},
         {"shape", p.panel.shape == PsychometricShape::kWeibull ? "weibull" : "cumulative normal"},
         {"counts", counts},
         {"curve", curve}});
  }
  return rows;
}

// The ratings, thresholds (jnd) and tuning sections (study/statistics/ratings.h,
// thresholds.h, tuning.h). The thresholds are kept for tuning's
// perceptual steps and for the psychometric plots.
void add_ratings_thresholds_tuning(std::vector<AnalysisSection>& sections) {
  sections.push_back({"ratings",
                      [](const TrialsTable& table) {
                        const auto observations = rating_observations(table);
                        if (observations.empty()) return nlohmann::json(nullptr);
                        const RatingsResult ratings = fit_ratings(observations);
                        return nlohmann::json{{"ratings", ratings.to_json()},
                                              {"ratings_models", ratings.models_json()}};
                      },
                      {}});
  auto thresholds = std::make_shared<std::optional<ThresholdsResult>>();
  sections.push_back({"jnd",
                      [thresholds](const TrialsTable& table) {
                        const auto observations = stronger_observations(table);
                        if (observations.empty()) return nlohmann::json(nullptr);
                        *thresholds = fit_thresholds(observations);
                        return nlohmann::json{{"jnd", (*thresholds)->to_json()},
                                              {"jnd_levels", jnd_levels_json(**thresholds)}};
                      },
                      [thresholds] {
                        std::vector<AnalysisPlot> plots;
                        if (!*thresholds) return plots;
                        for (const ParameterThresholds& p : (*thresholds)->parameters)
                          plots.push_back({plot_file_name(kJndPlotPrefix, p.parameter),
                                           "Psychometric function: " + p.parameter,
                                           render_psychometric_plot(p)});
                        return plots;
                      }});
  auto tuning = std::make_shared<std::optional<TuningResult>>();
  sections.push_back({"tuning",
                      [thresholds, tuning](const TrialsTable& table) {
                        const auto doors =
                            tuned_doors(table, std::filesystem::path(table.source).parent_path());
                        if (doors.empty()) return nlohmann::json(nullptr);
                        TuningOptions options;
                        if (*thresholds)
                          options.measured_weber = measured_weber_fractions(**thresholds);
                        *tuning = analyze_tuning(doors, options);
                        return nlohmann::json{{"tuning", (*tuning)->to_json()}};
                      },
                      [tuning] {
                        std::vector<AnalysisPlot> plots;
                        if (!*tuning) return plots;
                        try {
                          plots.push_back({kTuningPlotFile, "The panel's tuned doors",
                                           render_tuning_plot(**tuning)});
                        } catch (const std::invalid_argument&) {
                          // No parameter has perceptual steps: nothing to draw (the JSON says why).
                        }
                        return plots;
                      }});
}

}  // namespace

std::vector<AnalysisSection> analysis_sections(const AnalysisOptions& options,
                                               const AnalysisProgress& progress) {
  std::vector<AnalysisSection> sections;
  sections.push_back({"preference",
                      [options, progress](const TrialsTable& table) {
                        const PairData data = pair_data(table);
                        if (data.trials.empty()) return nlohmann::json(nullptr);
                        PreferenceOptions preference = options.preference;
                        preference.confidence = options.confidence;
                        const auto report = [&](int done, int total) {
                          if (progress) progress("preference bootstrap", done, total);
                        };
                        return preference_scale_json(
                            fit_preference_scale(data, preference, report));
                      },
                      {}});
  sections.push_back({"identify_real",
                      [options](const TrialsTable& table) {
                        const auto result =
                            identify_real(table, options.real_variant, options.confidence,
                                          options.equivalence_dprime);
                        if (!result) return nlohmann::json(nullptr);
                        return nlohmann::json{{"identify_real", identify_real_json(*result)}};
                      },
                      {}});
  sections.push_back({"two_ac",
                      [options](const TrialsTable& table) {
                        const auto pairs =
                            two_ac_pairs(table, options.confidence, options.equivalence_dprime);
                        if (pairs.empty()) return nlohmann::json(nullptr);
                        return nlohmann::json{{"two_ac", two_ac_json(pairs)}};
                      },
                      {}});
  add_ratings_thresholds_tuning(sections);
  // A further section: one entry here, a function of the table returning an object of
  // analysis.json keys (or null when the table has none of its trials); report.html shows a
  // key it does not know as a generic table.
  return sections;
}

nlohmann::json analyze_trials(const TrialsTable& table, const AnalysisOptions& options,
                              const AnalysisProgress& progress,
                              std::vector<AnalysisPlot>* section_plots) {
  if (const std::string problem = options.validate(); !problem.empty())
    throw std::invalid_argument("analysis options: " + problem);
  nlohmann::json analysis = nlohmann::json::object();
  std::set<std::string> participants;
  for (std::size_t r = 0; r < table.rows.size(); ++r)
    participants.insert(table.value(r, "participant"));
  analysis["input"] = {{"trials_table", table.source},
                       {"rows", table.rows.size()},
                       {"participants", participants.size()},
                       {"confidence", options.confidence}};
  nlohmann::json sections = nlohmann::json::array();
  AnalysisOptions stoppable = options;
  if (!stoppable.preference.stop_requested) {
    stoppable.preference.stop_requested = options.stop_requested;
  }
  for (const AnalysisSection& section : analysis_sections(stoppable, progress)) {
    nlohmann::json keys;
    try {
      throw_if_stop_requested(options.stop_requested, "the " + section.name + " section");
      keys = section.make(table);
    } catch (const StopRequested& stop) {
      analysis["interrupted"] =
          "during " + stop.where() + ": it and the sections after it were not computed";
      break;
    }
    sections.push_back({{"name", section.name}, {"found", !keys.is_null()}});
    if (keys.is_null()) continue;
    for (const auto& [key, value] : keys.items()) analysis[key] = value;
    if (section_plots != nullptr && section.plots) {
      for (AnalysisPlot& plot : section.plots()) section_plots->push_back(std::move(plot));
    }
  }
  analysis["sections"] = sections;
  return analysis;
}

namespace {
// A number for the terminal: 2 decimals, "n/a" for null (not estimable), no "-0.00".
std::string plain(const nlohmann::json& value) {
  if (!value.is_number()) return value.is_string() ? value.get<std::string>() : "n/a";
  return format_fixed(value.get<double>(), 2);
}
}  // namespace

std::string analysis_summary(const nlohmann::json& a) {
  std::string text;
  auto cell = plain;
  if (a.contains("preference_scale")) {
    text += "preference scale (worth [95% interval]):";
    for (const auto& w : a["preference_scale"])
      text += " " + w["variant"].get<std::string>() + " " + cell(w["worth"]) +
              (w.value("interval", "") == "reference"
                   ? " (reference)"
                   : " [" + cell(w["ci_low"]) + ", " + cell(w["ci_high"]) + "]");
    text += "\n";
    const nlohmann::json* favourite = nullptr;
    for (const auto& w : a["preference_scale"])
      if (favourite == nullptr || w["p_favourite"] > (*favourite)["p_favourite"]) favourite = &w;
    if (favourite != nullptr)
      text += "favourite: " + (*favourite)["variant"].get<std::string>() + " (probability " +
              cell((*favourite)["p_favourite"]) + ")\n";
    for (const auto& note : a["preference_fit"]["notes"]) text += "note: " + cell(note) + "\n";
  }
  if (a.contains("ties"))
    text += "ties: nu " + cell(a["ties"]["nu"]) + " [" + cell(a["ties"]["ci_low"]) + ", " +
            cell(a["ties"]["ci_high"]) + "]\n";
  if (a.contains("identify_real"))
    text += "identify-real: " + cell(a["identify_real"]["verdict"]) + "\n";
  if (a.contains("two_ac"))
    for (const auto& r : a["two_ac"]) {
      text += "2-AC " + r["first"].get<std::string>() + " vs " + r["second"].get<std::string>() +
              ": " + cell(r["verdict"]);
      const std::string note = r.value("note", "");
      text += note.empty() ? "\n" : " (" + note + ")\n";
    }
  return text;
}

}  // namespace doorbench::study
