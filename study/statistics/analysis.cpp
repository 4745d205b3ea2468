#include "study/statistics/analysis.h"

#include <cmath>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <memory>
#include <optional>
#include <set>

#include "acquisition/session/output_file.h"
#include "core/number_format.h"
#include "analysis/report/svg_plot.h"
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
    rows.push_back({{"parameter", p.parameter},
                    {"reference", p.reference},
                    {"shape", p.panel.shape == PsychometricShape::kWeibull ? "weibull"
                                                                           : "cumulative normal"},
                    {"counts", counts}});
  }
  return rows;
}

// The ratings, thresholds (jnd) and tuning sections (issue 29's other half,
// study/statistics/ratings.h, thresholds.h, tuning.h). The thresholds are kept for tuning's
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
                          plots.push_back({"jnd-" + p.parameter + ".svg",
                                           "Psychometric function: " + p.parameter,
                                           render_psychometric_plot(p)});
                        return plots;
                      }});
  auto tuning = std::make_shared<std::optional<TuningResult>>();
  sections.push_back(
      {"tuning",
       [thresholds, tuning](const TrialsTable& table) {
         const auto doors = tuned_doors(table, std::filesystem::path(table.source).parent_path());
         if (doors.empty()) return nlohmann::json(nullptr);
         TuningOptions options;
         if (*thresholds) options.measured_weber = measured_weber_fractions(**thresholds);
         *tuning = analyze_tuning(doors, options);
         return nlohmann::json{{"tuning", (*tuning)->to_json()}};
       },
       [tuning] {
         std::vector<AnalysisPlot> plots;
         if (!*tuning) return plots;
         try {
           plots.push_back({"tuning.svg", "The panel's tuned doors", render_tuning_plot(**tuning)});
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
                        const auto result = identify_real(table, options.real_variant,
                                                          options.confidence,
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
  for (const AnalysisSection& section : analysis_sections(options, progress)) {
    const nlohmann::json keys = section.make(table);
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

std::string escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

std::string cell(const nlohmann::json& value) {
  if (value.is_null()) return "&ndash;";
  if (value.is_number_float()) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", value.get<double>());
    return text;
  }
  if (value.is_string()) return escape(value.get<std::string>());
  return escape(value.dump());
}

// An array of objects as a table, the columns in the first object's order (a subset of
// keys when `columns` is given).
std::string table_of(const nlohmann::json& rows, std::vector<std::string> columns = {}) {
  if (!rows.is_array() || rows.empty()) return "<p>None.</p>\n";
  if (columns.empty())
    for (const auto& [key, value] : rows.front().items()) columns.push_back(key);
  std::string html = "<table><tr>";
  for (const std::string& c : columns) html += "<th>" + escape(c) + "</th>";
  html += "</tr>\n";
  for (const nlohmann::json& row : rows) {
    html += "<tr>";
    for (const std::string& c : columns)
      html += "<td>" + (row.contains(c) ? cell(row[c]) : std::string("&ndash;")) + "</td>";
    html += "</tr>\n";
  }
  return html + "</table>\n";
}

// A value without words of its own: an array of objects as a table; an object's members each
// under a heading, the same way; anything else as JSON text.
std::string generic_html(const nlohmann::json& value) {
  if (value.is_array() && !value.empty() && value.front().is_object()) return table_of(value);
  if (value.is_object()) {
    std::string html;
    for (const auto& [key, member] : value.items())
      html += "<h3>" + escape(key) + "</h3>\n" +
              (member.is_array() && !member.empty() && member.front().is_object()
                   ? table_of(member)
                   : "<pre>" + escape(member.dump(2)) + "</pre>\n");
    return html;
  }
  return "<pre>" + escape(value.dump(2)) + "</pre>\n";
}

std::string figure(const std::vector<AnalysisPlot>& plots, const std::string& file) {
  for (const AnalysisPlot& plot : plots)
    if (plot.file == file) return "<figure>" + plot.svg + "</figure>\n";
  return "";
}

// One plotted estimate with its interval.
struct Interval {
  std::string label;
  double value, low, high;
};

// Each estimate as its own series: a vertical bar over the interval with a tick at the
// estimate, at x = 1, 2, ... in the given order (the legend names them).
std::string interval_plot(const std::string& title, const std::string& y_label,
                          const std::vector<Interval>& items) {
  std::vector<std::vector<double>> xs, ys;
  std::vector<std::string> labels;
  for (std::size_t k = 0; k < items.size(); ++k) {
    const Interval& i = items[k];
    if (!std::isfinite(i.value) || !std::isfinite(i.low) || !std::isfinite(i.high)) continue;
    const double x = double(k + 1);
    xs.push_back({x, x, x - 0.15, x + 0.15, x, x});
    ys.push_back({i.low, i.value, i.value, i.value, i.value, i.high});
    labels.push_back(std::to_string(k + 1) + ": " + i.label);
  }
  if (xs.empty()) return "";
  std::vector<PlotSeries> series;
  for (std::size_t s = 0; s < xs.size(); ++s) series.push_back({labels[s], xs[s], ys[s], "", {}});
  PlotOptions options;
  options.title = title;
  options.x_label = "estimate number (legend)";
  options.y_label = y_label;
  return render_svg_plot(options, series);
}

double number_or_nan(const nlohmann::json& value) {
  return value.is_number() ? value.get<double>() : std::nan("");
}

// A name for a file: every character outside [A-Za-z0-9._-] as '_'.
std::string file_safe(const std::string& name) {
  std::string out;
  for (const char c : name) {
    const bool plain = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                       c == '.' || c == '_' || c == '-';
    out += plain ? c : '_';
  }
  return out;
}

// The panel's psychometric curve with its data, from the jnd rows and jnd_levels.
void add_psychometric_plots(const nlohmann::json& analysis, std::vector<AnalysisPlot>& plots) {
  if (!analysis.contains("jnd_levels") || !analysis.contains("jnd")) return;
  for (const nlohmann::json& levels : analysis["jnd_levels"]) {
    ParameterThresholds t;
    t.parameter = levels.at("parameter").get<std::string>();
    t.reference = levels.at("reference").get<std::string>();
    for (const nlohmann::json& c : levels.at("counts"))
      t.counts.push_back({c.at("log_ratio").get<double>(), c.at("trials").get<int>(),
                          c.at("stronger").get<int>()});
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
    plots.push_back({"jnd-" + file_safe(t.parameter) + ".svg",
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
    if (row.at("weber_fraction").is_number()) d.weber_fraction = row["weber_fraction"].get<double>();
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
    plots.push_back({"tuning.svg", "The panel's tuned doors", render_tuning_plot(t)});
  } catch (const std::invalid_argument&) {
    // No parameter has perceptual steps: nothing to draw (the JSON says why).
  }
}

}  // namespace

std::vector<AnalysisPlot> analysis_plots(const nlohmann::json& analysis) {
  std::vector<AnalysisPlot> plots;
  auto add = [&](const std::string& file, const std::string& title, const std::string& y,
                 const std::vector<Interval>& items) {
    const std::string svg = interval_plot(title, y, items);
    if (!svg.empty()) plots.push_back({file, title, svg});
  };
  if (analysis.contains("preference_scale")) {
    std::vector<Interval> items;
    for (const auto& w : analysis["preference_scale"])
      items.push_back({w["variant"].get<std::string>(), number_or_nan(w["worth"]),
                       number_or_nan(w["ci_low"]), number_or_nan(w["ci_high"])});
    add("preference-scale.svg", "Preference scale (Bradley-Terry worths, 95 % intervals)",
        "worth (log scale) [-]", items);
  }
  if (analysis.contains("identify_real")) {
    std::vector<Interval> items;
    const auto& ir = analysis["identify_real"];
    items.push_back({"panel", number_or_nan(ir["panel"]["dprime"]),
                     number_or_nan(ir["panel"]["ci_low"]), number_or_nan(ir["panel"]["ci_high"])});
    for (const auto& p : ir["participants"])
      items.push_back({p["participant"].get<std::string>(), number_or_nan(p["dprime"]),
                       number_or_nan(p["ci_low"]), number_or_nan(p["ci_high"])});
    add("identify-real.svg", "Real vs virtual: d' (2-AFC), 95 % intervals", "d' [-]", items);
  }
  if (analysis.contains("two_ac")) {
    std::vector<Interval> items;
    for (const auto& r : analysis["two_ac"])
      items.push_back({r["first"].get<std::string>() + " vs " + r["second"].get<std::string>(),
                       number_or_nan(r["dprime"]), number_or_nan(r["ci_low"]),
                       number_or_nan(r["ci_high"])});
    add("two-ac.svg", "2-AC: d' per pair (> 0: second preferred), 95 % intervals", "d' [-]", items);
  }
  if (analysis.contains("ratings") && analysis.contains("ratings_models")) {
    for (const auto& model : analysis["ratings_models"]) {
      if (!model.value("converged", false)) continue;  // the table says so; no picture of it
      const std::string attribute = model.at("attribute").get<std::string>();
      std::vector<Interval> items;
      for (const auto& r : analysis["ratings"])
        if (r.at("attribute") == attribute)
          items.push_back({r.at("variant").get<std::string>(), number_or_nan(r["estimate"]),
                           number_or_nan(r["ci_low"]), number_or_nan(r["ci_high"])});
      add("ratings-" + file_safe(attribute) + ".svg",
          "Ratings of " + attribute + ": each variant's shift on the latent scale, 95 % intervals",
          "shift against the reference variant (logit) [-]", items);
    }
  }
  add_psychometric_plots(analysis, plots);
  add_tuning_plot(analysis, plots);
  return plots;
}

namespace {

std::string preference_html(const nlohmann::json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Preference scale</h2>\n<p>Bradley&ndash;Terry worths on the log scale (the first "
      "variant at 0); a worth difference of 1 means odds of e&nbsp;&asymp;&nbsp;2.7 to 1 for the "
      "better variant. p_favourite: the probability that the variant is the panel's favourite. "
      "interval: which standard error made the interval (the model's Wald SE or the "
      "participant bootstrap's, whichever is larger).</p>\n";
  html += table_of(a["preference_scale"], {"variant", "worth", "ci_low", "ci_high", "interval",
                                           "p_favourite", "wins", "losses", "ties"});
  if (a.contains("ties"))
    html += "<p>Davidson's tie parameter &nu; = " + cell(a["ties"]["nu"]) + " [" +
            cell(a["ties"]["ci_low"]) + ", " + cell(a["ties"]["ci_high"]) + "].</p>\n";
  if (a.contains("order_effect"))
    html += "<p>First-position advantage &delta; = " + cell(a["order_effect"]["delta"]) + " [" +
            cell(a["order_effect"]["ci_low"]) + ", " + cell(a["order_effect"]["ci_high"]) +
            "] (log odds; 0: the order does not matter).</p>\n";
  for (const auto& note : a["preference_fit"]["notes"])
    html += "<p class=\"small\">" + cell(note) + "</p>\n";
  return html + figure(plots, "preference-scale.svg");
}

std::string identify_html(const nlohmann::json& ir, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Real vs virtual (identify-real)</h2>\n<p><b>" + cell(ir["verdict"]) + "</b></p>\n";
  nlohmann::json rows = nlohmann::json::array();
  nlohmann::json panel = ir["panel"];
  panel["participant"] = "panel";
  rows.push_back(panel);
  for (const auto& p : ir["participants"]) rows.push_back(p);
  html += table_of(rows, {"participant", "n", "correct", "pc", "dprime", "ci_low", "ci_high", "p"});
  return html + figure(plots, "identify-real.svg");
}

}  // namespace

std::string analysis_html(const nlohmann::json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Campaign analysis</title>\n"
      "<style>@page{size:A4 portrait;margin:14mm 12mm}body{font-family:sans-serif;"
      "font-size:9.5pt;max-width:46em;margin:1em auto}h1{font-size:16pt}h2{font-size:12.5pt}"
      "table{border-collapse:collapse;margin:0.6em 0;max-width:100%;font-size:8pt}td,th{border:1px "
      "solid #bbb;"
      "padding:1px "
      "4px;text-align:right;overflow-wrap:anywhere}td:first-child,th:first-child{text-align:left}"
      ".small{font-size:8.5pt;color:#333}svg{max-width:100%;height:auto}</style></head><body>\n"
      "<h1>Campaign analysis</h1>\n";
  const auto& input = a["input"];
  html += "<p>" + cell(input["trials_table"]) + ": " + cell(input["rows"]) + " trials, " +
          cell(input["participants"]) + " participants; intervals at " + cell(input["confidence"]) +
          ".</p>\n";
  std::set<std::string> shown{"input",        "sections",  "preference_fit",
                              "ties",         "order_effect", "jnd_levels"};
  if (a.contains("preference_scale")) {
    html += preference_html(a, plots);
    shown.insert("preference_scale");
  }
  if (a.contains("identify_real")) {
    html += identify_html(a["identify_real"], plots);
    shown.insert("identify_real");
  }
  if (a.contains("two_ac")) {
    html +=
        "<h2>2-AC preference (preference-2ac)</h2>\n<p>Thurstonian &tau; and d' per pair "
        "(d' &gt; 0: the second variant preferred; interval: profile likelihood).</p>\n" +
        table_of(a["two_ac"], {"first", "second", "prefer_first", "no_preference", "prefer_second",
                               "tau", "dprime", "ci_low", "ci_high", "p", "note"}) +
        figure(plots, "two-ac.svg");
    shown.insert("two_ac");
  }
  for (const auto& [key, value] : a.items()) {  // sections without words here (ratings, ...)
    if (shown.count(key)) continue;
    html += "<h2>" + escape(key) + "</h2>\n" + generic_html(value);
    if (key == "jnd" || key == "tuning" || key == "ratings") {
      for (const AnalysisPlot& plot : plots)
        if (plot.file.rfind(key, 0) == 0) html += "<figure>" + plot.svg + "</figure>\n";
    }
  }
  return html + "</body></html>\n";
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

std::string render_pdf(const std::filesystem::path& html_path,
                       const std::filesystem::path& pdf_path, const std::string& renderer_in) {
  std::string renderer = renderer_in;
  if (renderer.empty()) {
    if (std::system("command -v weasyprint > /dev/null 2>&1") != 0)
      return "weasyprint is not installed (scripts/install-deps.sh installs it)";
    renderer = "weasyprint";
  }
  const std::filesystem::path partial = partial_path_for(pdf_path);
  std::filesystem::path log = pdf_path;
  log += ".log";
  auto quote = [](const std::filesystem::path& path) {
    std::string out = "'";
    for (char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
  };
  const std::string command =
      renderer + " " + quote(html_path) + " " + quote(partial) + " > " + quote(log) + " 2>&1";
  std::error_code ignored;
  if (std::system(command.c_str()) != 0 || !std::filesystem::exists(partial)) {
    std::filesystem::remove(partial, ignored);
    return renderer + " failed (see " + log.string() + ")";
  }
  commit_partial_file(partial, pdf_path);
  std::filesystem::remove(log, ignored);
  return "";
}

}  // namespace doorbench::study
