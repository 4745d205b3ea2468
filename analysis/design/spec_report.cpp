#include "analysis/design/spec_report.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "acquisition/session/pdf_output.h"
#include "analysis/design/internal/spec_text.h"
#include "analysis/report/svg_plot.h"
#include "core/html_escape.h"
#include "core/number_format.h"
#include "core/numbers.h"
#include "core/units.h"

namespace doorbench {

using design_detail::felt_criterion_text;

namespace {

std::string cell(double value, const char* format = "%.4g") {
  return std::isfinite(value) ? printf_text(format, value) : std::string("&ndash;");
}

// The parts a design changes, "F0 250 -> 219.6 N (-12 %)", and their names.
std::vector<const DesignParameter*> changed_parts(const DesignSolution& solution) {
  std::vector<const DesignParameter*> parts;
  for (const DesignParameter& p : solution.parameters) {
    if (p.changed) parts.push_back(&p);
  }
  return parts;
}

std::string change_text(const DesignParameter& p) {
  std::string text = p.name + printf_text(" %.5g &rarr; %.5g %s", p.as_is, p.to_be, p.unit.c_str());
  if (std::isfinite(p.relative_change)) text += printf_text(" (%+.1f %%)", 100 * p.relative_change);
  return text;
}

std::string inline_svg(const PlotOptions& options, std::span<const PlotSeries> series) {
  try {
    std::string svg = render_svg_plot(options, series);
    if (svg.rfind("<?xml", 0) == 0) svg.erase(0, svg.find('\n') + 1);
    // Scaled to the page's width: a viewBox of the drawn size, the width the column's.
    const std::string size =
        printf_text("width=\"%d\" height=\"%d\"", options.width_px, options.height_px);
    if (const std::size_t at = svg.find(size); at != std::string::npos) {
      svg.replace(at, size.size(),
                  printf_text("viewBox=\"0 0 %d %d\" width=\"100%%\" style=\"max-width:%dpx\"",
                              options.width_px, options.height_px, options.width_px));
    }
    return "<figure>" + svg + "</figure>\n";
  } catch (const std::invalid_argument& error) {
    return "<p>(" + html_escape(options.title) + ": no plot, " + html_escape(error.what()) +
           ")</p>\n";
  }
}

struct CurveSeries {
  std::vector<double> x, y;
};

CurveSeries curve_series(const ForceAngleCurve& curve, bool opening) {
  CurveSeries out;
  const auto& force = opening ? curve.opening_force_N : curve.closing_force_N;
  for (std::size_t b = 0; b < curve.angle_rad.size(); ++b) {
    out.x.push_back(curve.angle_rad[b] * kDegPerRad);
    out.y.push_back(force[b]);  // NaN: a gap in the line
  }
  return out;
}

// The felt quantities of the AS-IS model, the design and the recordings, all read along the
// TO-BE recordings' own motion (the check's model forces): one definition, one condition.
std::string felt_table(const SpecEvaluation& e, const FeltOptions& felt) {
  std::string html =
      "<p class=\"small\">Read along the TO-BE recordings' own motion (each model's hand force "
      "by inverse dynamics on the recorded angle and rate): " +
      html_escape(felt_definition(felt)) +
      ".</p>\n<table><tr><th>quantity</th><th>AS-IS model</th><th>design</th>"
      "<th>TO-BE recorded</th><th>design &minus; recorded</th></tr>\n";
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    const double recorded = e.check_after.recorded.*info.member;
    const double after = e.check_after.model.*info.member;
    html += "<tr><td>" + html_escape(felt_label(info)) + "</td><td>" +
            cell(e.check_before.model.*info.member, "%.2f") + "</td><td>" + cell(after, "%.2f") +
            "</td><td>" + cell(recorded, "%.2f") + "</td><td>" + cell(after - recorded, "%+.2f") +
            "</td></tr>\n";
  }
  html += printf_text(
      "<tr><td>force&ndash;angle curve RMS error (N)</td><td>%s</td><td>%s</td><td></td>"
      "<td></td></tr>\n",
      cell(e.check_before.curve_rms_error_N, "%.2f").c_str(),
      cell(e.check_after.curve_rms_error_N, "%.2f").c_str());
  return html + "</table>\n";
}

// The standard run (the virtual hand): AS-IS and design under the same, stated conditions.
std::string standard_run_table(const SpecEvaluation& e, const FeltOptions& felt) {
  std::string html =
      "<p class=\"small\">The same quantities in the standard run (" +
      html_escape(standard_run_conditions(felt)) +
      "), as the tolerance analysis reads them. Its speeds differ from the recordings', so its "
      "figures compare with each other, not with the table above.</p>\n"
      "<table><tr><th>quantity, standard run</th><th>AS-IS door</th><th>design</th>"
      "<th>change</th></tr>\n";
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    const double before = e.felt_before.*info.member;
    const double after = e.felt_after.*info.member;
    html += "<tr><td>" + html_escape(felt_label(info)) + "</td><td>" + cell(before, "%.2f") +
            "</td><td>" + cell(after, "%.2f") + "</td><td>" + cell(after - before, "%+.2f") +
            "</td></tr>\n";
  }
  return html + "</table>\n";
}

// A histogram of quantity q over the Monte Carlo samples: counts in 20 bins from the
// smallest to the largest, and the nominal value.
std::string spread_histogram(const ToleranceResult& t, std::size_t q) {
  const QuantitySpread& s = t.spreads[q];
  if (s.count < 2 || !(s.max > s.min)) return "";
  constexpr int kBins = 20;
  std::vector<double> x(kBins), y(kBins, 0.0);
  const double width = (s.max - s.min) / kBins;
  for (int b = 0; b < kBins; ++b) x[b] = s.min + (b + 0.5) * width;
  for (const FeltQuantities& felt : t.felt) {
    const double v = felt.*kFeltQuantities[q].member;
    if (!std::isfinite(v)) continue;
    y[std::min(kBins - 1, static_cast<int>((v - s.min) / width))] += 1;
  }
  const std::vector<double> nominal_x = {s.nominal, s.nominal};
  const std::vector<double> nominal_y = {0.0, *std::max_element(y.begin(), y.end())};
  const PlotSeries series[] = {{"samples per bin", x, y, ""},
                               {"nominal", nominal_x, nominal_y, "#000000"}};
  PlotOptions options;
  options.title = "spread of the " + std::string(kFeltQuantities[q].label);
  options.x_label = felt_label(kFeltQuantities[q]);
  options.y_label = "samples";
  options.width_px = 480;
  options.height_px = 280;
  return "<div class=\"half\">" + inline_svg(options, series) + "</div>";
}

std::string tolerance_section(const ToleranceResult& t, const FeltOptions& felt) {
  std::string html = printf_text(
      "<p>%d samples of the design within the tolerances below (%d failed), %d threads, "
      "%.1f s; each sample's felt quantities from the standard run (",
      t.samples, t.failed, t.threads, t.elapsed_s);
  html += html_escape(standard_run_conditions(felt)) + ").</p>\n";
  html +=
      "<table><tr><th>quantity</th><th>nominal</th><th>mean</th><th>sd</th><th>p5</th>"
      "<th>p95</th><th>most important tolerance</th></tr>\n";
  for (std::size_t q = 0; q < t.spreads.size(); ++q) {
    const QuantitySpread& s = t.spreads[q];
    double share = 0;
    for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
      if (t.tolerances[p].name == t.most_important[q]) share = t.explained[q][p];
    }
    html +=
        "<tr><td>" + html_escape(felt_label(kFeltQuantities[q])) + "</td><td>" +
        cell(s.nominal, "%.2f") + "</td><td>" + cell(s.mean, "%.2f") + "</td><td>" +
        cell(s.sd, "%.2f") + "</td><td>" + cell(s.p5, "%.2f") + "</td><td>" + cell(s.p95, "%.2f") +
        "</td><td>" +
        (t.most_important[q].empty() ? std::string("&ndash;")
                                     : html_escape(t.most_important[q]) +
                                           printf_text(" (%.0f %% of the variance)", 100 * share)) +
        "</td></tr>\n";
  }
  html += "</table>\n";
  for (std::size_t q = 0; q < t.spreads.size(); ++q) html += spread_histogram(t, q);
  html +=
      "<h3>Tolerances used</h3><table><tr><th>parameter</th><th>&plusmn;</th>"
      "<th>distribution</th><th>nominal</th></tr>\n";
  for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
    const ParameterTolerance& tol = t.tolerances[p];
    html +=
        "<tr><td>" + html_escape(tol.name) + "</td><td>" +
        (tol.percent ? printf_text("%g %%", tol.plus_minus) : printf_text("%g", tol.plus_minus)) +
        "</td><td>" + std::string(to_string(tol.distribution)) + "</td><td>" +
        cell(t.nominal_values[p], "%.5g") + "</td></tr>\n";
  }
  return html + "</table>\n";
}

std::string share_cell(const PerceptualRow& row) {
  if (!std::isfinite(row.share)) return "&ndash; (" + html_escape(row.note) + ")";
  return printf_text("%.1f %% [%.1f, %.1f] (%d of %d)", 100 * row.share, 100 * row.ci_low,
                     100 * row.ci_high, row.felt_different, row.doors);
}

std::string tolerance_text(const ParameterTolerance& t) {
  return t.percent ? printf_text("%.3g %%", t.plus_minus) : printf_text("%.3g", t.plus_minus);
}

// The panel's preference scale and thresholds, as analysis.json gave them.
std::string panel_tables(const PerceptualSpec& p) {
  std::string html;
  if (!p.preference.empty()) {
    html +=
        "<h3>The panel's preference scale</h3><table><tr><th>variant</th>"
        "<th>worth (log scale)</th><th>95 % interval</th></tr>\n";
    for (const PanelPreference& v : p.preference) {
      html += "<tr><td>" + html_escape(v.variant) + "</td><td>" + cell(v.worth, "%.3g") +
              "</td><td>" + cell(v.ci_low, "%.3g") + " to " + cell(v.ci_high, "%.3g") +
              "</td></tr>\n";
    }
    html += "</table>\n";
  }
  if (!p.thresholds.empty()) {
    html +=
        "<h3>Thresholds measured (panel)</h3><table><tr><th>parameter</th><th>reference</th>"
        "<th>method</th><th>JND (Weber fraction)</th><th>95 % interval</th><th>criterion</th>"
        "</tr>\n";
    for (const PanelThreshold& t : p.thresholds) {
      html += "<tr><td>" + html_escape(t.parameter) + "</td><td>" + html_escape(t.reference) +
              "</td><td>" + html_escape(t.method) + "</td><td>" +
              cell(100 * t.weber_fraction, "%.1f %%") + "</td><td>" + cell(100 * t.ci_low, "%.1f") +
              " to " + (std::isfinite(t.ci_high) ? cell(100 * t.ci_high, "%.1f %%") : "open") +
              "</td><td>" + html_escape(t.criterion) + "</td></tr>\n";
    }
    html += "</table>\n";
  }
  return html;
}

// The perceptual tolerance table beside the engineering one, and the proposal.
std::string perceptual_section(const PerceptualSpec& p) {
  std::string html = "<p>From the panel: " + html_escape(p.campaign) +
                     ". TO-BE feel: " + html_escape(p.tobe_source) + ".</p>\n";
  if (!p.notes.empty()) {
    html += "<ul class=\"small\">\n";
    for (const std::string& note : p.notes) html += "<li>" + html_escape(note) + "</li>\n";
    html += "</ul>\n";
  }
  html += panel_tables(p);
  html += "<h3>Doors a panel member would feel as different</h3><p class=\"small\">" +
          html_escape(felt_criterion_text()) + ".</p>\n";
  html +=
      "<table><tr><th>quantity</th><th>nominal</th><th>JND</th><th>JND from</th>"
      "<th>felt as different, tolerances as given</th><th>at the proposed tolerances</th></tr>\n";
  for (std::size_t q = 0; q < p.rows.size(); ++q) {
    const PerceptualRow& row = p.rows[q];
    html +=
        "<tr><td>" + html_escape(felt_label(kFeltQuantities[q])) + "</td><td>" +
        cell(row.nominal, "%.2f") + "</td><td>" + cell(100 * row.jnd.weber_fraction, "%.1f %%") +
        "</td><td>" + html_escape(row.jnd.source) + "</td><td>" + share_cell(row) + "</td><td>" +
        (q < p.proposal.rows.size() ? share_cell(p.proposal.rows[q]) : "&ndash;") + "</td></tr>\n";
  }
  html += "</table>\n<p>Proposed (level " + cell(100 * p.proposal.felt_share, "%.3g %%") +
          "): " + html_escape(p.proposal.summary) + ".</p>\n";
  html +=
      "<table><tr><th>parameter</th><th>&plusmn; as given</th><th>&plusmn; proposed</th>"
      "<th>distribution</th></tr>\n";
  for (const ParameterTolerance& t : p.proposal.tolerances) {
    ParameterTolerance given = t;
    given.plus_minus = t.plus_minus / p.proposal.factor;
    html += "<tr><td>" + html_escape(t.name) + "</td><td>" + tolerance_text(given) + "</td><td>" +
            tolerance_text(t) + "</td><td>" + std::string(to_string(t.distribution)) +
            "</td></tr>\n";
  }
  return html + "</table>\n";
}

}  // namespace

std::string SpecEvaluationOptions::validate() const {
  if (std::string error = felt.validate(); !error.empty()) return error;
  if (std::string error = equivalence.validate(); !error.empty()) return error;
  if (run_tolerances) return monte_carlo.validate();
  return "";
}

SpecEvaluation evaluate_spec(const DoorModel& asis, const InverseDesignResult& design,
                             std::span<const PreparedData> tobe,
                             const SpecEvaluationOptions& options) {
  if (std::string error = options.validate(); !error.empty()) throw std::invalid_argument(error);
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  SpecEvaluation e;
  e.warnings = design.felt_miss_warnings();
  const DoorModel& tobe_model = design.solutions.front().model;
  e.felt_before = felt_quantities(asis, options.felt);
  e.felt_after = felt_quantities(tobe_model, options.felt);
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    e.felt_alternatives.push_back(felt_quantities(design.solutions[s].model, options.felt));
  }
  EquivalenceOptions equivalence = options.equivalence;
  equivalence.felt = options.felt;
  e.equivalence = assess_equivalence(design, equivalence);
  e.equivalence_criterion = equivalence_criterion(equivalence);
  e.check_before = compare_feel(asis, tobe, options.felt);
  e.check_after = compare_feel(tobe_model, tobe, options.felt);
  e.felt = options.felt;
  if (options.run_tolerances) {
    MonteCarloOptions mc = options.monte_carlo;
    mc.felt = options.felt;
    const ToleranceSpec spec =
        options.tolerances.parameters.empty() ? default_tolerances(tobe_model) : options.tolerances;
    try {
      e.tolerances = tolerance_analysis(tobe_model, spec, mc);
    } catch (const StopRequested& stop) {
      e.interrupted = "during " + stop.where() + ": no tolerance analysis";
      e.warnings.push_back("interrupted " + e.interrupted);
    }
  }
  for (const PreparedData& d : tobe) e.tobe_sources.push_back(d.source);
  return e;
}

namespace {

constexpr const char* kStyle =
    "<style>@page{size:A4 portrait;margin:14mm 12mm}"
    "body{font-family:sans-serif;font-size:9.5pt;max-width:46em;margin:1em auto;"
    "overflow-wrap:break-word}"
    "h1{font-size:16pt}h2{font-size:12.5pt;margin-top:1.2em}h3{font-size:10.5pt}"
    "table{border-collapse:collapse;margin:0.6em 0;max-width:100%}"
    "td,th{border:1px solid #bbb;padding:1px 5px;text-align:right;overflow-wrap:break-word}"
    "td:first-child,th:first-child{text-align:left}tr.changed{background:#fff4cc}"
    "tr{page-break-inside:avoid}.bad{color:#b00}.small{font-size:8.5pt;color:#333}"
    "code{overflow-wrap:anywhere;word-break:break-all}figure{margin:0.6em 0}"
    "svg{max-width:100%;height:auto}.half{display:inline-block;width:49%}"
    ".todo{border:2px solid #1f5fbf;padding:0.4em 0.8em;margin:0.8em 0}"
    ".todo p{margin:0.2em 0}td.l{text-align:left}</style>";

// The first page's three lines: what to change, what stays, what it gives.
std::string what_to_change(const InverseDesignResult& design, const SpecEvaluation& e) {
  const DesignSolution& best = design.solutions.front();
  const std::vector<const DesignParameter*> parts = changed_parts(best);
  std::string change;
  for (const DesignParameter* p : parts) change += (change.empty() ? "" : "; ") + change_text(*p);
  int kept = 0;
  for (const DesignParameter& p : best.parameters) kept += p.changed ? 0 : 1;
  std::string html =
      "<div class=\"todo\">\n<p><b>Change:</b> " +
      (parts.empty() ? std::string("nothing (the AS-IS door already fits)") : change) + ".</p>\n";
  html += printf_text(
      "<p><b>Keep</b> the other %d parameters as they are (parts changed: %d, cost %.4g).</p>\n",
      kept, best.parts_changed, best.parts_changed_cost);
  html += printf_text(
      "<p><b>Result:</b> the force&ndash;angle curve along the TO-BE recordings misses them by "
      "%s N RMS (AS-IS door: %s N)%s.</p>\n</div>\n",
      cell(e.check_after.curve_rms_error_N, "%.2f").c_str(),
      cell(e.check_before.curve_rms_error_N, "%.2f").c_str(),
      design.feasible ? "" : "; the TO-BE feel lies outside the bounds (below)");
  return html;
}

std::string sources_section(const InverseDesignResult& design, const SpecEvaluation& e) {
  const DesignSolution& best = design.solutions.front();
  std::string html =
      "<p class=\"small\">AS-IS: " + html_escape(e.asis_source) + "<br>TO-BE recordings: ";
  for (std::size_t i = 0; i < e.tobe_sources.size(); ++i) {
    html += (i ? ", " : "") + html_escape(e.tobe_sources[i]);
  }
  html += "<br>made by: <code>" + html_escape(e.command) + "</code></p>\n";
  for (const std::string& warning : e.warnings) {
    html += "<p class=\"bad\">Warning: " + html_escape(warning) + "</p>\n";
  }
  if (!design.feasible) {
    html +=
        "<p class=\"bad\">Not reachable within the bounds; the design below is the nearest "
        "feasible one. " +
        html_escape(design.infeasibility) + "</p>\n";
  }
  html += printf_text(
      "<p class=\"small\">Fit of the TO-BE recordings by the design: window RMS error of the rate "
      "%.4g rad/s (the data's rate noise %.4g rad/s). A change counts when it is larger than "
      "its uncertainty and than a stated share of its bound width (docs/inverse-design.md).</p>\n",
      best.fit.window.rmse(), design.rate_noise_rad_s);
  if (design.commanded_torque) {
    html +=
        "<p class=\"small\">The TO-BE recordings are haptic playbacks: the design was fitted to "
        "the torque they commanded (the device's rendering is not in it), the inertia to their "
        "motion.</p>\n";
  }
  return html;
}

std::string parameter_section(const DesignSolution& best) {
  std::string html =
      "<h2>Parameters</h2><table><tr><th>parameter</th><th>AS-IS</th><th>design</th>"
      "<th>change</th><th>&plusmn;</th><th>unit</th><th></th></tr>\n";
  for (const DesignParameter& p : best.parameters) {
    html +=
        std::string(p.changed ? "<tr class=\"changed\">" : "<tr>") + "<td>" + html_escape(p.name) +
        "</td><td>" + cell(p.as_is, "%.5g") + "</td><td>" + cell(p.to_be, "%.5g") + "</td><td>" +
        (p.changed
             ? cell(p.change, "%+.4g") + (std::isfinite(p.relative_change)
                                              ? printf_text(" (%+.1f %%)", 100 * p.relative_change)
                                              : std::string())
             : std::string()) +
        "</td><td>" + cell(p.uncertainty, "%.2g") + "</td><td>" + html_escape(p.unit) +
        "</td><td>" + (p.free ? (p.at_bound ? "at bound" : "") : "fixed") + "</td></tr>\n";
  }
  return html + "</table>\n";
}

std::string sparse_section(const InverseDesignResult& design) {
  if (design.sparse_steps.empty()) return "";
  std::string html =
      "<h2>How the parts were chosen</h2>\n<p class=\"small\">From AS-IS, one more parameter "
      "at a time: the one whose refit lowers the data cost most (of those the data cannot tell "
      "apart, the smallest weighted change).</p>\n<table><tr><th>parts</th><th>added</th>"
      "<th>data cost</th><th>&phi;</th><th>the data cannot tell it from</th></tr>\n";
  for (std::size_t s = 0; s < design.sparse_steps.size(); ++s) {
    const SparseStep& step = design.sparse_steps[s];
    std::string same;
    for (const auto& [name, cost] : step.tried) {
      const bool equivalent =
          std::find(step.equivalent.begin(), step.equivalent.end(), name) != step.equivalent.end();
      if (name != step.added && equivalent) {
        same += (same.empty() ? "" : ", ") + html_escape(name) + printf_text(" (%.6g)", cost);
      }
    }
    html += printf_text("<tr><td>%zu</td><td>", s) +
            (s == 0 ? std::string("(AS-IS)") : html_escape(step.added)) + "</td><td>" +
            cell(step.data_cost, "%.6g") + "</td><td>" + cell(step.reduced_data_cost, "%.3g") +
            "</td><td>" + same + "</td></tr>\n";
  }
  return html + "</table>\n<p class=\"small\">" + html_escape(design.sparse_stop) + ".</p>\n";
}

std::string curve_plot(const SpecEvaluation& e) {
  const CurveSeries rec_o = curve_series(e.check_after.recorded_curve, true);
  const CurveSeries rec_c = curve_series(e.check_after.recorded_curve, false);
  const CurveSeries asis_o = curve_series(e.check_before.model_curve, true);
  const CurveSeries asis_c = curve_series(e.check_before.model_curve, false);
  const CurveSeries tobe_o = curve_series(e.check_after.model_curve, true);
  const CurveSeries tobe_c = curve_series(e.check_after.model_curve, false);
  const PlotSeries series[] = {
      {"TO-BE recorded, opening", rec_o.x, rec_o.y, "#000000"},
      {"TO-BE recorded, closing", rec_c.x, rec_c.y, "#777777"},
      {"AS-IS model, opening", asis_o.x, asis_o.y, "#c0392b"},
      {"AS-IS model, closing", asis_c.x, asis_c.y, "#e6a09a"},
      {"design, opening", tobe_o.x, tobe_o.y, "#1f5fbf"},
      {"design, closing", tobe_c.x, tobe_c.y, "#8fb0e6"},
  };
  PlotOptions options;
  options.title = "hand force against angle along the TO-BE recordings' motion";
  options.x_label = "angle (deg)";
  options.y_label = "hand force (N)";
  return inline_svg(options, series);
}

std::string alternatives_section(const InverseDesignResult& design, const SpecEvaluation& e) {
  std::string html = "<h2>Alternatives</h2>\n";
  if (design.solutions.size() < 2) {
    return html + "<p>No other design fits the recordings equally well.</p>\n";
  }
  html +=
      "<table><tr><th>#</th><th>parts</th><th>cost</th><th>data cost</th><th>changes</th>"
      "<th>equivalent to the design?</th></tr>\n";
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    const DesignSolution& alt = design.solutions[s];
    std::string changes;
    if (!alt.swapped.empty()) {
      changes = "<em>sparse design, " + html_escape(alt.swapped) + "</em>: ";
    } else if (!alt.held_at_as_is.empty()) {
      changes = "<em>fewest changes</em>: ";
    } else if (alt.start_index >= 0) {
      changes = "<em>smallest change</em>: ";
    }
    for (const DesignParameter* p : changed_parts(alt)) changes += change_text(*p) + "; ";
    html += printf_text("<tr><td>%zu</td><td>%d</td><td>%.4g</td><td>%.6g</td><td class=\"l\">",
                        s + 1, alt.parts_changed, alt.parts_changed_cost, alt.data_cost) +
            changes + "</td><td class=\"l\">" +
            (s - 1 < e.equivalence.size()
                 ? (e.equivalence[s - 1].equivalent ? "<b>equivalent</b>: " : "") +
                       html_escape(e.equivalence[s - 1].verdict)
                 : std::string()) +
            "</td></tr>\n";
  }
  return html + "</table>\n<p class=\"small\">Equivalent: " + html_escape(e.equivalence_criterion) +
         ".</p>\n";
}

}  // namespace

std::string spec_summary(const InverseDesignResult& design, const SpecEvaluation& e) {
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  const DesignSolution& best = design.solutions.front();
  std::string text = "What to change:";
  for (const DesignParameter* p : changed_parts(best)) {
    text +=
        printf_text(" %s %.5g -> %.5g %s", p->name.c_str(), p->as_is, p->to_be, p->unit.c_str());
    if (std::isfinite(p->relative_change))
      text += printf_text(" (%+.1f %%)", 100 * p->relative_change);
    text += ";";
  }
  if (best.parts_changed == 0) text += " nothing;";
  text += printf_text("\nKeep everything else (parts changed: %d, cost %.4g).\n",
                      best.parts_changed, best.parts_changed_cost);
  text += printf_text(
      "Force-angle curve along the TO-BE recordings: RMS error %.2f N (AS-IS door %.2f N).\n",
      e.check_after.curve_rms_error_N, e.check_before.curve_rms_error_N);
  text += "\nfelt along the TO-BE recordings' motion (" + felt_definition(e.felt) + "):\n";
  text += printf_text("  %-34s %9s %9s %9s %9s\n", "quantity", "AS-IS", "design", "recorded",
                      "des-rec");
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    const double after = e.check_after.model.*info.member;
    const double recorded = e.check_after.recorded.*info.member;
    text += printf_text("  %-34s %9.2f %9.2f %9.2f %+9.2f\n", felt_label(info).c_str(),
                        e.check_before.model.*info.member, after, recorded, after - recorded);
  }
  text += "felt in the standard run (" + standard_run_conditions(e.felt) + "):\n";
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    text += printf_text("  %-34s %9.2f %9.2f\n", felt_label(info).c_str(),
                        e.felt_before.*info.member, e.felt_after.*info.member);
  }
  if (!e.equivalence.empty()) {
    text += "alternatives (" + e.equivalence_criterion + "):\n";
    for (const SolutionEquivalence& q : e.equivalence) {
      text += printf_text("  #%zu %s\n", q.solution + 1, q.verdict.c_str());
    }
  }
  return text;
}

std::string spec_html(const InverseDesignResult& design, const SpecEvaluation& e) {
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Door design "
      "specification</title>\n" +
      std::string(kStyle) + "</head><body>\n<h1>Door design specification</h1>\n";
  html += what_to_change(design, e);
  html += sources_section(design, e);
  html += "<h2>What it feels like</h2>\n" + felt_table(e, e.felt) + curve_plot(e);
  html += standard_run_table(e, e.felt);
  html += parameter_section(design.solutions.front());
  html += sparse_section(design);
  html += alternatives_section(design, e);
  html += "<h2>Manufacturing tolerances</h2>\n";
  html += e.tolerances ? tolerance_section(*e.tolerances, e.felt)
                       : std::string("<p>Not analysed.</p>\n");
  if (e.perceptual) {
    html += "<h2>Tolerances judged by the panel's perception</h2>\n" +
            perceptual_section(*e.perceptual);
  }
  if (!design.notes.empty()) {
    html += "<h2>Notes</h2><ul class=\"small\">\n";
    for (const std::string& note : design.notes) html += "<li>" + html_escape(note) + "</li>\n";
    html += "</ul>\n";
  }
  return html + "</body></html>\n";
}

SpecReportFiles write_spec_report(const std::filesystem::path& dir,
                                  const InverseDesignResult& design,
                                  const SpecEvaluation& evaluation, const std::string& pdf_renderer,
                                  const StopHook& stop) {
  std::error_code ignored;
  std::filesystem::create_directories(dir, ignored);
  SpecReportFiles files;
  files.json = dir / "spec.json";
  files.html = dir / "spec.html";
  // Whole or not at all, the error naming the path (acquisition/session/output_file.h).
  auto write = [](const std::filesystem::path& path, const std::string& text) {
    write_text_file_atomically(path, text);
  };
  write(files.json, spec_json(design, evaluation));
  write(files.html, spec_html(design, evaluation));

  const std::filesystem::path pdf = dir / "spec.pdf";
  if (pdf_renderer == "none") {
    remove_output_not_written(pdf);
    files.pdf_note = "no PDF (not asked for)";
    return files;
  }
  const std::string problem = render_pdf(files.html, pdf, pdf_renderer, stop);
  if (problem.empty()) {
    files.pdf = pdf;
    files.pdf_note = "PDF rendered by " + (pdf_renderer.empty() ? "weasyprint" : pdf_renderer);
  } else {
    files.pdf_note = "no PDF: " + problem;
  }
  return files;
}

}  // namespace doorbench
