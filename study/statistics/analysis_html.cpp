// report.html of a campaign analysis (study/statistics/analysis.h, analysis_html): each known
// section as a table with the model's words, its numbers with the digits a reader needs (an
// estimate to 2 decimals, a p-value as "< 0.001" or to 3 significant digits), every number
// and name kept on one line (the PDF never breaks one), the plots inline.
#include <cmath>
#include <regex>
#include <set>

#include "core/html_escape.h"
#include "core/number_format.h"
#include "study/statistics/analysis.h"

namespace doorbench::study {
namespace {

using json = nlohmann::json;

// "[low, high]" of two cells, built piece by piece (GCC 12 warns falsely, -Wrestrict, on
// "literal" + std::string).
std::string bracketed(const std::string& low, const std::string& high) {
  std::string out = "[";
  out.append(low).append(", ").append(high).append("]");
  return out;
}

double value_of(const json& value) {
  return value.is_number() ? value.get<double>() : std::nan("");
}

// A number with `decimals` decimals, "–" for null (not estimable).
std::string html_fixed(const json& value, int decimals = 2) {
  if (value.is_null()) return "&ndash;";
  return html_escape(format_fixed(value_of(value), decimals));
}

// "[low, high]", an open end written as ∞.
std::string html_interval(const json& low, const json& high, int decimals = 2) {
  auto end = [&](const json& v, const char* open) {
    return v.is_number() ? html_escape(format_fixed(v.get<double>(), decimals)) : std::string(open);
  };
  if (low.is_null() && high.is_null()) return "&ndash;";
  return bracketed(end(low, "&minus;&infin;"), end(high, "&infin;"));
}

std::string p_cell(const json& value) {
  return value.is_number() ? html_escape(format_p_value(value.get<double>())) : "&ndash;";
}

// "NAME = 0.148" or "NAME &lt; 0.001" in a sentence.
std::string p_sentence(const std::string& name, const json& value) {
  if (!value.is_number()) return name + " &ndash;";
  const std::string text = format_p_value(value.get<double>());
  return name + (text.front() == '<' || text.front() == '>' ? " " : " = ") + html_escape(text);
}

// A sentence for HTML with its numbers kept together: no line break inside "d' 0.22",
// "[-0.75, 1.20]", "p = 0.804" or "p < 0.001".
std::string sentence(const json& value) {
  std::string text = html_escape(value.is_string() ? value.get<std::string>() : value.dump());
  text = std::regex_replace(text, std::regex("\\[([^\\] ]*), ([^\\]]*)\\]"), "[$1,&nbsp;$2]");
  text = std::regex_replace(text, std::regex("(d'|\\|d'\\|) (-?[0-9]|inf)"), "$1&nbsp;$2");
  return std::regex_replace(text, std::regex("\\bp (=|&lt;|&gt;) "), "p&nbsp;$1&nbsp;");
}

// Any other value of a generic table: 3 significant digits for a number, text as it is.
std::string html_cell(const json& value) {
  if (value.is_null()) return "&ndash;";
  if (value.is_number_float()) return html_escape(format_significant(value.get<double>(), 3));
  if (value.is_string()) return html_escape(value.get<std::string>());
  return html_escape(value.dump());
}

// A cell whose text may wrap between words (a sentence): marked by a leading '\t'.
std::string wrappable(const std::string& text) {
  std::string out = "\t";
  out += text;
  return out;
}

// One table: headers (HTML allowed) and rows of cells (HTML). A cell marked wrappable is
// written with class "text" (the mark dropped); every other cell stays on one line.
std::string html_table(const std::vector<std::string>& headers,
                       const std::vector<std::vector<std::string>>& rows) {
  std::string html = "<table><tr>";
  for (const std::string& h : headers) html += "<th>" + h + "</th>";
  html += "</tr>\n";
  for (const auto& row : rows) {
    html += "<tr>";
    for (const std::string& c : row)
      html += !c.empty() && c.front() == '\t' ? "<td class=\"text\">" + c.substr(1) + "</td>"
                                              : "<td>" + c + "</td>";
    html += "</tr>\n";
  }
  return html + "</table>\n";
}

std::string html_figure(const std::vector<AnalysisPlot>& plots, const std::string& file) {
  for (const AnalysisPlot& plot : plots)
    if (plot.file == file) return "<figure>" + plot.svg + "</figure>\n";
  return "";
}

std::string figures_starting(const std::vector<AnalysisPlot>& plots, const std::string& prefix) {
  std::string html;
  for (const AnalysisPlot& plot : plots)
    if (plot.file.rfind(prefix, 0) == 0) html += "<figure>" + plot.svg + "</figure>\n";
  return html;
}

// An array of objects as a table, the columns in the first object's order.
std::string generic_table(const json& rows) {
  if (!rows.is_array() || rows.empty()) return "<p>None.</p>\n";
  std::vector<std::string> headers, keys;
  for (const auto& [key, value] : rows.front().items()) {
    keys.push_back(key);
    headers.push_back(html_escape(key));
  }
  std::vector<std::vector<std::string>> cells;
  for (const json& row : rows) {
    std::vector<std::string> line;
    for (const std::string& k : keys) {
      const std::string text = row.contains(k) ? html_cell(row[k]) : "&ndash;";
      line.push_back(row.contains(k) && row[k].is_string() ? wrappable(text) : text);
    }
    cells.push_back(line);
  }
  return html_table(headers, cells);
}

// A value without words of its own: an array of objects as a table; an object's members each
// under a heading, the same way; anything else as JSON text.
std::string generic_html(const json& value) {
  if (value.is_array() && !value.empty() && value.front().is_object()) return generic_table(value);
  if (value.is_object()) {
    std::string html;
    for (const auto& [key, member] : value.items())
      html += "<h3>" + html_escape(key) + "</h3>\n" + generic_html(member);
    return html;
  }
  return "<p class=\"small\">" + html_escape(value.dump()) + "</p>\n";
}

std::string preference_html(const json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Preference scale</h2>\n<p>Bradley&ndash;Terry worths on the log scale (the reference "
      "at 0), best first; a worth difference of 1 means odds of e&nbsp;&asymp;&nbsp;2.7 to 1 for "
      "the better variant. <i>95 % interval</i>: of the worth against the reference. "
      "<i>Comparison interval</i>: worth &plusmn; 1.39 quasi-standard errors (Firth &amp; de "
      "Menezes 2004): two variants whose comparison intervals do not overlap differ at about the "
      "5 % level, whichever two. <i>P(fav.)</i>: the probability that the variant is the panel's "
      "favourite. <i>SE</i>: which standard error made the interval (the model's Wald SE or the "
      "participant bootstrap's, whichever is larger).</p>\n";
  std::vector<json> worths(a["preference_scale"].begin(), a["preference_scale"].end());
  std::stable_sort(worths.begin(), worths.end(), [](const json& x, const json& y) {
    return value_of(x["worth"]) > value_of(y["worth"]);
  });
  std::vector<std::vector<std::string>> rows;
  for (const json& w : worths) {
    const bool reference = w.value("interval", "") == "reference";
    rows.push_back(
        {html_escape(w["variant"].get<std::string>()) + (reference ? " (ref.)" : ""),
         html_fixed(w["worth"]), reference ? "&ndash;" : html_interval(w["ci_low"], w["ci_high"]),
         html_interval(w.value("comparison_low", json()), w.value("comparison_high", json())),
         html_fixed(w.value("quasi_se", json()), 3), html_fixed(w["p_favourite"]),
         html_cell(w["wins"]), html_cell(w["losses"]), html_cell(w["ties"]),
         reference ? "&ndash;" : html_cell(w["interval"])});
  }
  html += html_table({"variant", "worth", "95 % interval", "comparison interval", "quasi-SE",
                      "P(fav.)", "wins", "losses", "ties", "SE"},
                     rows);
  if (a.contains("ties"))
    html += "<p>Davidson's tie parameter &nu; = " + html_fixed(a["ties"]["nu"]) + " " +
            html_interval(a["ties"]["ci_low"], a["ties"]["ci_high"]) + ".</p>\n";
  if (a.contains("order_effect"))
    html += "<p>First-position advantage &delta; = " + html_fixed(a["order_effect"]["delta"]) +
            " " + html_interval(a["order_effect"]["ci_low"], a["order_effect"]["ci_high"]) +
            " (log odds; 0: the order does not matter).</p>\n";
  for (const auto& note : a["preference_fit"]["notes"])
    html += "<p class=\"small\">" + sentence(note) + "</p>\n";
  return html + html_figure(plots, kPreferencePlotFile);
}

std::vector<std::string> forced_choice_row(const std::string& who, const json& r) {
  return {who,
          html_cell(r["n"]),
          html_cell(r["correct"]),
          html_fixed(r["pc"]),
          html_fixed(r["dprime"]),
          html_interval(r["ci_low"], r["ci_high"]),
          p_cell(r["p"])};
}

std::string identify_html(const json& ir, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Real vs virtual (identify-real)</h2>\n<p><b>" + sentence(ir["verdict"]) + "</b></p>\n";
  html +=
      "<p class=\"small\">d' = &radic;2&middot;&Phi;<sup>&minus;1</sup>(Pc) (2-AFC); 95 % "
      "interval from the Clopper&ndash;Pearson interval of Pc; p: the exact binomial test "
      "of chance. Equivalence: the two one-sided tests against &plusmn;" +
      html_fixed(ir.value("equivalence_margin", json()), 2) + " (--equivalence-dprime): " +
      p_sentence("p<sub>TOST</sub>", ir["panel"].value("p_equivalence", json())) +
      "; the verdict says the doors are indistinguishable only when the whole 95 % interval "
      "lies inside the margin.</p>\n";
  std::vector<std::vector<std::string>> rows{forced_choice_row("<b>panel</b>", ir["panel"])};
  for (const auto& p : ir["participants"])
    rows.push_back(forced_choice_row(html_escape(p["participant"].get<std::string>()), p));
  html += html_table({"participant", "trials", "correct", "Pc", "d'", "95 % interval", "p"}, rows);
  return html + html_figure(plots, kIdentifyPlotFile);
}

std::string two_ac_html(const json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>2-AC preference (preference-2ac)</h2>\n<p>Thurstonian &tau; and d' per pair "
      "(Christensen, Lee &amp; Brockhoff 2012; d' &gt; 0: the second variant preferred; "
      "interval: profile likelihood; p: the likelihood-root test of d' = 0). Equivalence: the "
      "two one-sided tests against &plusmn;" +
      html_fixed(a["two_ac"].front().value("equivalence_margin", json()), 2) +
      " (--equivalence-dprime), p<sub>TOST</sub>; a pair is called indistinguishable only when "
      "its whole 95 % interval lies inside the margin.</p>\n";
  std::vector<std::vector<std::string>> rows;
  std::string verdicts;
  for (const json& r : a["two_ac"]) {
    std::string pair = html_escape(r["first"].get<std::string>());
    pair.append(" vs ").append(html_escape(r["second"].get<std::string>()));
    rows.push_back({pair, html_cell(r["prefer_first"]), html_cell(r["no_preference"]),
                    html_cell(r["prefer_second"]), html_fixed(r["tau"]), html_fixed(r["dprime"]),
                    html_interval(r["ci_low"], r["ci_high"]), p_cell(r["p"]),
                    p_cell(r.value("p_equivalence", json()))});
    verdicts.append("<li><b>").append(pair).append("</b>: ").append(
        sentence(r.value("verdict", json(""))));
    if (!r.value("note", "").empty())
      verdicts.append(" (").append(html_cell(r["note"])).append(")");
    verdicts.append("</li>\n");
  }
  html += html_table({"pair (A vs B)", "prefer A", "same", "prefer B", "&tau;", "d'",
                      "95 % interval", "p", "p<sub>TOST</sub>"},
                     rows);
  html += "<ul class=\"small\">\n" + verdicts + "</ul>\n";
  return html + html_figure(plots, kTwoAcPlotFile);
}

std::string ratings_html(const json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Ratings</h2>\n<p>Per attribute, a cumulative-logit model with a random intercept per "
      "participant (clmm; clm when the participants' spread is 0): each variant's shift on the "
      "latent scale against the reference (&gt; 0: rated higher), with its Wald 95 % "
      "interval.</p>\n";
  for (const json& model : a.value("ratings_models", json::array())) {
    const std::string attribute = model.value("attribute", "");
    html += "<h3>" + html_escape(attribute) + "</h3>\n<p class=\"small\">" +
            html_cell(model.value("model", json(""))) + ", " +
            html_cell(model.value("observations", json(0))) + " ratings by " +
            html_cell(model.value("participants", json(0))) + " participants; participant SD " +
            html_fixed(model.value("participant_sd", json())) +
            (model.value("converged", false) ? "" : "; <b>the fit did not converge</b>") +
            ".</p>\n";
    std::vector<std::vector<std::string>> rows;
    for (const json& r : a["ratings"]) {
      if (r.value("attribute", "") != attribute) continue;
      const bool reference = r.value("reference", false);
      rows.push_back({html_escape(r["variant"].get<std::string>()) + (reference ? " (ref.)" : ""),
                      html_fixed(r["estimate"]),
                      reference ? "&ndash;" : html_interval(r["ci_low"], r["ci_high"]),
                      reference ? "&ndash;" : html_fixed(r["std_error"], 3)});
    }
    html += html_table({"variant", "shift", "95 % interval", "SE"}, rows);
    html += html_figure(plots, plot_file_name(kRatingsPlotPrefix, attribute));
  }
  return html;
}

// A Weber fraction as a percentage, 1 decimal; past 1000 % (ten times the reference, a
// profile end the data barely bound) written "> 1000".
std::string percent_cell(const json& value) {
  if (!value.is_number()) return "&ndash;";
  const double percent = 100 * value.get<double>();
  return percent > 1000 ? "&gt; 1000" : html_escape(format_fixed(percent, 1));
}

// The method in a few words: a staircase's rule and reversals, a fit.
std::string jnd_method(const json& r) {
  const std::string method = r.value("method", "");
  if (method == "staircase reversals")
    return "staircase 1-up-" + html_cell(r.value("down_rule", json(0))) + "-down, " +
           html_cell(r.value("reversals", json(0))) + " rev.";
  if (method == "psychometric fit, pooled") return "pooled fit";
  if (method == "psychometric fit") return "fit";
  return html_escape(method);
}

std::string jnd_html(const json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<h2>Thresholds (jnd)</h2>\n<p>The JND as a Weber fraction in percent, read on the "
      "lapse-free psychometric function; its 95 % interval from the profile likelihood "
      "(&infin; above: the data do not bound it). PSE and spread on ln(comparison / "
      "reference). A staircase's JND is the mean of its last reversals, its interval a t "
      "interval over them (indicative), at the percent correct its 1-up-N-down rule "
      "tracks.</p>\n";
  std::set<std::string> done;
  for (const json& first : a["jnd"]) {
    const std::string key = first.value("parameter", "") + "|" + first.value("reference", "");
    if (!done.insert(key).second) continue;
    html += "<h3>" + html_escape(first.value("parameter", "")) + " around " +
            html_escape(first.value("reference", "")) + "</h3>\n<p class=\"small\">" +
            html_escape(first.value("criterion", "")) + ".</p>\n";
    std::vector<std::vector<std::string>> rows;
    for (const json& r : a["jnd"]) {
      if (r.value("parameter", "") + "|" + r.value("reference", "") != key) continue;
      const std::string who = html_escape(r.value("participant", ""));
      rows.push_back(
          {who == "panel" ? "<b>panel</b>" : who, jnd_method(r), percent_cell(r["weber_fraction"]),
           r["ci_low"].is_number()
               ? bracketed(percent_cell(r["ci_low"]),
                           r["ci_high"].is_number() ? percent_cell(r["ci_high"]) : "&infin;")
               : "&ndash;",
           html_fixed(r.value("pse", json()), 3), html_fixed(r.value("spread", json()), 3),
           html_fixed(r.value("lapse", json()), 3), html_cell(r.value("trials", json()))});
    }
    html += html_table(
        {"participant", "method", "JND %", "95 % interval %", "PSE", "spread", "lapse", "trials"},
        rows);
    html += html_figure(plots, plot_file_name(kJndPlotPrefix, first.value("parameter", "")));
  }
  return html;
}

std::string tuning_html(const json& t, const std::vector<AnalysisPlot>& plots) {
  std::string html = "<h2>Tuned doors</h2>\n<p>Per parameter over the panel's ";
  html.append(std::to_string(t.value("doors", json::array()).size()))
      .append(
          " tuned doors: the centre (geometric mean on the log scale) with its 95 % interval, "
          "the spread, and the spread in perceptual steps (ln differences over ln(1 + Weber "
          "fraction), the Weber fraction's source named).</p>\n");
  std::vector<std::vector<std::string>> rows;
  for (const json& p : t.value("parameters", json::array())) {
    rows.push_back({html_escape(p.value("parameter", "")), html_cell(p["centre"]),
                    bracketed(html_cell(p["ci_low"]), html_cell(p["ci_high"])),
                    html_cell(p["spread"]), percent_cell(p["weber_fraction"]),
                    html_cell(p["weber_source"]), html_fixed(p["spread_steps"]),
                    html_fixed(p["ci_half_steps"])});
  }
  html += html_table({"parameter", "centre", "95 % interval", "spread", "Weber %", "source",
                      "spread, steps", "&plusmn; steps"},
                     rows);
  if (t.contains("clusters")) {
    const json& c = t["clusters"];
    html += "<p class=\"small\">" +
            std::string(c.value("split", false) ? "The panel splits in two groups"
                                                : "One group (no split)") +
            ": " + html_cell(c.value("rule", json(""))) + "; separation " +
            html_fixed(c.value("separation", json())) + " steps.</p>\n";
  }
  return html + html_figure(plots, kTuningPlotFile);
}

const char* kStyle =
    "<style>@page{size:A4 portrait;margin:14mm 12mm}body{font-family:sans-serif;"
    "font-size:9.5pt;max-width:46em;margin:1em auto}h1{font-size:16pt}h2{font-size:12.5pt;"
    "margin-top:1.4em}h3{font-size:10.5pt}table{border-collapse:collapse;margin:0.6em 0;"
    "font-size:8pt}td,th{border:1px solid #bbb;padding:1px 4px;text-align:right;"
    "white-space:nowrap}th{white-space:normal;vertical-align:bottom;font-weight:600}"
    "td.text{white-space:normal;text-align:left;min-width:10em}"
    "td:first-child,th:first-child{text-align:left}.small{font-size:8.5pt;color:#333}"
    "figure{margin:0.6em 0;break-inside:avoid}svg{max-width:100%;height:auto}</style>";

}  // namespace

std::string analysis_html(const json& a, const std::vector<AnalysisPlot>& plots) {
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Campaign analysis</title>\n" +
      std::string(kStyle) + "</head><body>\n<h1>Campaign analysis</h1>\n";
  const auto& input = a["input"];
  const int people = input.value("participants", 0);
  html += "<p>" + html_cell(input["trials_table"]) + ": " + html_cell(input["rows"]) + " trials, " +
          std::to_string(people) + (people == 1 ? " participant" : " participants") +
          "; intervals at " + html_escape(format_fixed(100 * value_of(input["confidence"]), 0)) +
          " %.</p>\n";
  std::set<std::string> shown{"input",        "sections",   "preference_fit", "ties",
                              "order_effect", "jnd_levels", "ratings_models"};
  const auto known = [&](const char* key, auto&& render) {
    if (!a.contains(key)) return;
    html += render();
    shown.insert(key);
  };
  known("preference_scale", [&] { return preference_html(a, plots); });
  known("identify_real", [&] { return identify_html(a["identify_real"], plots); });
  known("two_ac", [&] { return two_ac_html(a, plots); });
  known("ratings", [&] { return ratings_html(a, plots); });
  known("jnd", [&] { return jnd_html(a, plots); });
  known("tuning", [&] { return tuning_html(a["tuning"], plots); });
  for (const auto& [key, value] : a.items()) {  // keys without words here
    if (shown.count(key)) continue;
    html +=
        "<h2>" + html_escape(key) + "</h2>\n" + generic_html(value) + figures_starting(plots, key);
  }
  return html + "</body></html>\n";
}

}  // namespace doorbench::study
