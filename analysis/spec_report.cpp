#include "analysis/spec_report.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "acquisition/output_file.h"
#include "analysis/svg_plot.h"
#include "analysis/text_format.h"

namespace doorbench {

namespace {

using json = nlohmann::ordered_json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = 180.0 / 3.14159265358979323846;

// NaN and infinities become null (JSON has no NaN).
json number(double value) {
  return std::isfinite(value) ? json(value) : json(nullptr);
}

json felt_json(const FeltQuantities& felt) {
  json out = json::object();
  for (const FeltQuantityInfo& info : kFeltQuantities) {
    out[std::string(info.name)] = number(felt.*info.member);
  }
  out["unlatch_angle_rad"] = number(felt.unlatch_angle_rad);
  out["balance_angle_rad"] = number(felt.balance_angle_rad);
  return out;
}

json check_json(const FeelCheck& check) {
  json errors = json::array();
  for (const FeltQuantityError& e : check.errors) {
    errors.push_back({{"name", e.name},
                      {"model", number(e.model)},
                      {"recorded", number(e.recorded)},
                      {"error", number(e.error)},
                      {"error_percent", number(e.error_percent)}});
  }
  return {{"errors", errors},
          {"curve_rms_error_N", number(check.curve_rms_error_N)},
          {"opening_rms_error_N", number(check.opening_rms_error_N)},
          {"closing_rms_error_N", number(check.closing_rms_error_N)},
          {"bins_compared", check.bins_compared}};
}

json parameter_json(const DesignParameter& p) {
  return {{"name", p.name},
          {"unit", p.unit},
          {"free", p.free},
          {"as_is", number(p.as_is)},
          {"to_be", number(p.to_be)},
          {"change", number(p.change)},
          {"relative_change", number(p.relative_change)},
          {"uncertainty", number(p.uncertainty)},
          {"cost_of_change", number(p.weight)},
          {"bounds", {number(p.bounds.lower), number(p.bounds.upper)}},
          {"at_bound", p.at_bound}};
}

std::string escape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string cell(double value, const char* format = "%.4g") {
  return std::isfinite(value) ? printf_text(format, value) : std::string("&ndash;");
}

// A changed parameter: more than a part in a million of its bound width.
bool changed(const DesignParameter& p) {
  return std::abs(p.change) > 1e-6 * std::max(1e-12, p.bounds.upper - p.bounds.lower);
}

std::string inline_svg(const PlotOptions& options, std::span<const PlotSeries> series) {
  try {
    std::string svg = render_svg_plot(options, series);
    if (svg.rfind("<?xml", 0) == 0) svg.erase(0, svg.find('\n') + 1);
    return "<figure>" + svg + "</figure>\n";
  } catch (const std::invalid_argument& error) {
    return "<p>(" + escape(options.title) + ": no plot, " + escape(error.what()) + ")</p>\n";
  }
}

struct CurveSeries {
  std::vector<double> x, y;
};

CurveSeries curve_series(const ForceAngleCurve& curve, bool opening) {
  CurveSeries out;
  const auto& force = opening ? curve.opening_force_N : curve.closing_force_N;
  for (std::size_t b = 0; b < curve.angle_rad.size(); ++b) {
    out.x.push_back(curve.angle_rad[b] * kDeg);
    out.y.push_back(force[b]);  // NaN: a gap in the line
  }
  return out;
}

std::string felt_table(const SpecEvaluation& e) {
  std::string html =
      "<table><tr><th>quantity</th><th>AS-IS door</th><th>TO-BE design</th>"
      "<th>TO-BE recordings</th><th>design &minus; recordings</th></tr>\n";
  for (std::size_t q = 0; q < kFeltQuantities.size(); ++q) {
    const FeltQuantityInfo& info = kFeltQuantities[q];
    const double recorded = e.check_after.recorded.*info.member;
    const double after = e.felt_after.*info.member;
    html += "<tr><td>" + std::string(info.label) + " (" + std::string(info.unit) + ")</td><td>" +
            cell(e.felt_before.*info.member, "%.2f") + "</td><td>" + cell(after, "%.2f") +
            "</td><td>" + cell(recorded, "%.2f") + "</td><td>" + cell(after - recorded, "%+.2f") +
            "</td></tr>\n";
  }
  return html + "</table>\n";
}

std::string check_table(const FeelCheck& before, const FeelCheck& after) {
  std::string html =
      "<table><tr><th>quantity</th><th>recorded</th><th>AS-IS model</th><th>error</th>"
      "<th>TO-BE model</th><th>error</th></tr>\n";
  for (std::size_t q = 0; q < after.errors.size(); ++q) {
    const FeltQuantityError& a = after.errors[q];
    const FeltQuantityError& b = before.errors[q];
    html += "<tr><td>" + a.name + "</td><td>" + cell(a.recorded, "%.2f") + "</td><td>" +
            cell(b.model, "%.2f") + "</td><td>" + cell(b.error, "%+.2f") + " (" +
            cell(b.error_percent, "%+.1f") + " %)</td><td>" + cell(a.model, "%.2f") + "</td><td>" +
            cell(a.error, "%+.2f") + " (" + cell(a.error_percent, "%+.1f") + " %)</td></tr>\n";
  }
  html += "<tr><td>force&ndash;angle curve RMS (N)</td><td></td><td></td><td>" +
          cell(before.curve_rms_error_N, "%.2f") + "</td><td></td><td>" +
          cell(after.curve_rms_error_N, "%.2f") + "</td></tr>\n";
  return html + "</table>\n";
}

std::string tolerance_section(const ToleranceResult& t) {
  std::string html = printf_text(
      "<p>%d samples of the TO-BE design within the tolerances below (%d failed), %d threads, "
      "%.1f s.</p>\n",
      t.samples, t.failed, t.threads, t.elapsed_s);
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
        "<tr><td>" + s.name + "</td><td>" + cell(s.nominal, "%.2f") + "</td><td>" +
        cell(s.mean, "%.2f") + "</td><td>" + cell(s.sd, "%.2f") + "</td><td>" + cell(s.p5, "%.2f") +
        "</td><td>" + cell(s.p95, "%.2f") + "</td><td>" +
        (t.most_important[q].empty() ? std::string("&ndash;")
                                     : escape(t.most_important[q]) +
                                           printf_text(" (%.0f %% of the variance)", 100 * share)) +
        "</td></tr>\n";
  }
  html += "</table>\n";
  // A histogram per quantity: counts in 20 bins from the smallest to the largest sample.
  for (std::size_t q = 0; q < t.spreads.size(); ++q) {
    const QuantitySpread& s = t.spreads[q];
    if (s.count < 2 || !(s.max > s.min)) continue;
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
    options.title = "spread of " + std::string(kFeltQuantities[q].label);
    options.x_label = std::string(kFeltQuantities[q].name);
    options.y_label = "samples";
    options.width_px = 480;
    options.height_px = 280;
    html += inline_svg(options, series);
  }
  html +=
      "<h3>Tolerances used</h3><table><tr><th>parameter</th><th>&plusmn;</th>"
      "<th>distribution</th><th>nominal</th></tr>\n";
  for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
    const ParameterTolerance& tol = t.tolerances[p];
    html +=
        "<tr><td>" + escape(tol.name) + "</td><td>" +
        (tol.percent ? printf_text("%g %%", tol.plus_minus) : printf_text("%g", tol.plus_minus)) +
        "</td><td>" + std::string(to_string(tol.distribution)) + "</td><td>" +
        cell(t.nominal_values[p], "%.5g") + "</td></tr>\n";
  }
  return html + "</table>\n";
}

}  // namespace

std::string SpecEvaluationOptions::validate() const {
  if (std::string error = felt.validate(); !error.empty()) return error;
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
  const DoorModel& tobe_model = design.solutions.front().model;
  e.felt_before = felt_quantities(asis, options.felt);
  e.felt_after = felt_quantities(tobe_model, options.felt);
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    e.felt_alternatives.push_back(felt_quantities(design.solutions[s].model, options.felt));
  }
  e.check_before = compare_feel(asis, tobe, options.felt);
  e.check_after = compare_feel(tobe_model, tobe, options.felt);
  if (options.run_tolerances) {
    MonteCarloOptions mc = options.monte_carlo;
    mc.felt = options.felt;
    const ToleranceSpec spec =
        options.tolerances.parameters.empty() ? default_tolerances(tobe_model) : options.tolerances;
    e.tolerances = tolerance_analysis(tobe_model, spec, mc);
  }
  for (const PreparedData& d : tobe) e.tobe_sources.push_back(d.source);
  return e;
}

std::string spec_json(const InverseDesignResult& design, const SpecEvaluation& e) {
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  const DesignSolution& best = design.solutions.front();
  json root;
  root["about"] =
      "doorbench design specification: the physical door that feels like the TO-BE recordings "
      "with the smallest change to the AS-IS door (docs/design-spec.md)";
  root["command"] = e.command;
  root["asis_source"] = e.asis_source;
  root["tobe_sources"] = e.tobe_sources;
  root["feasible"] = design.feasible;
  root["infeasibility"] = design.infeasibility;
  // When infeasible: the binding parameters as the data ask for them (bounds widened).
  json requested = json::array();
  for (const DesignParameter& p : design.requested) requested.push_back(parameter_json(p));
  root["requested"] = requested;
  root["notes"] = design.notes;
  json parameters = json::array();
  for (const DesignParameter& p : best.parameters) parameters.push_back(parameter_json(p));
  root["parameters"] = parameters;
  root["fit"] = {{"window_rmse_rad_s", number(best.fit.window.rmse())},
                 {"rate_noise_rad_s", number(design.rate_noise_rad_s)},
                 {"misfit_factor", number(design.misfit_factor)},
                 {"commanded_torque", design.commanded_torque},
                 {"effective_regularization", number(design.effective_regularization)},
                 {"data_cost", number(best.data_cost)},
                 {"size_of_change", number(best.size_of_change)},
                 {"parts_changed_cost", number(best.parts_changed_cost)},
                 {"held_at_as_is", best.held_at_as_is},
                 {"converged", best.converged}};
  root["felt"] = {{"before", felt_json(e.felt_before)},
                  {"after", felt_json(e.felt_after)},
                  {"tobe_recorded", felt_json(e.check_after.recorded)}};
  root["check"] = {{"before", check_json(e.check_before)}, {"after", check_json(e.check_after)}};
  if (e.tolerances) {
    const ToleranceResult& t = *e.tolerances;
    json tolerances = json::array();
    for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
      const ParameterTolerance& tol = t.tolerances[p];
      tolerances.push_back({{"name", tol.name},
                            {"plus_minus", tol.plus_minus},
                            {"percent", tol.percent},
                            {"distribution", std::string(to_string(tol.distribution))},
                            {"absolute", number(tol.absolute(t.nominal_values[p]))}});
    }
    json spreads = json::array();
    for (std::size_t q = 0; q < t.spreads.size(); ++q) {
      const QuantitySpread& s = t.spreads[q];
      json explained = json::object();
      for (std::size_t p = 0; p < t.tolerances.size(); ++p) {
        explained[t.tolerances[p].name] = number(t.explained[q][p]);
      }
      spreads.push_back({{"name", s.name},
                         {"nominal", number(s.nominal)},
                         {"mean", number(s.mean)},
                         {"sd", number(s.sd)},
                         {"p5", number(s.p5)},
                         {"p95", number(s.p95)},
                         {"min", number(s.min)},
                         {"max", number(s.max)},
                         {"count", s.count},
                         {"most_important", t.most_important[q]},
                         {"explained_variance", explained}});
    }
    root["tolerances"] = {{"samples", t.samples},     {"failed", t.failed},
                          {"threads", t.threads},     {"elapsed_s", t.elapsed_s},
                          {"parameters", tolerances}, {"spreads", spreads}};
  } else {
    root["tolerances"] = nullptr;
  }
  json alternatives = json::array();
  for (std::size_t s = 1; s < design.solutions.size(); ++s) {
    const DesignSolution& alt = design.solutions[s];
    json changes = json::array();
    for (const DesignParameter& p : alt.parameters) {
      if (p.free && changed(p)) changes.push_back(parameter_json(p));
    }
    json entry = {{"index", s},
                  {"size_of_change", number(alt.size_of_change)},
                  {"parts_changed_cost", number(alt.parts_changed_cost)},
                  {"data_cost", number(alt.data_cost)},
                  {"window_rmse_rad_s", number(alt.fit.window.rmse())},
                  {"held_at_as_is", alt.held_at_as_is},
                  {"changes", changes}};
    if (s - 1 < e.felt_alternatives.size()) entry["felt"] = felt_json(e.felt_alternatives[s - 1]);
    alternatives.push_back(entry);
  }
  root["alternatives"] = alternatives;
  return root.dump(2) + "\n";
}

std::string spec_html(const InverseDesignResult& design, const SpecEvaluation& e) {
  if (design.solutions.empty())
    throw std::invalid_argument("spec: the inverse design has no solution");
  const DesignSolution& best = design.solutions.front();
  std::string html =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>Door design "
      "specification</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
      "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;padding:2px 8px;"
      "text-align:right}td:first-child,th:first-child{text-align:left}tr.changed{background:"
      "#fff4cc}.bad{color:#b00}figure{margin:1em 0}</style></head><body>\n"
      "<h1>Door design specification</h1>\n";
  html += "<p>AS-IS: " + escape(e.asis_source) + "<br>TO-BE recordings: ";
  for (std::size_t i = 0; i < e.tobe_sources.size(); ++i) {
    html += (i ? ", " : "") + escape(e.tobe_sources[i]);
  }
  html += "<br>made by: <code>" + escape(e.command) + "</code></p>\n";
  if (design.feasible) {
    html += "<p>The TO-BE feel is reachable within the parameters' bounds.</p>\n";
  } else {
    html +=
        "<p class=\"bad\">Not reachable within the bounds; the design below is the nearest "
        "feasible one. " +
        escape(design.infeasibility) + "</p>\n";
  }
  html += printf_text(
      "<p>Fit of the TO-BE recordings by the design: window RMS error of the rate %.4g rad/s "
      "(the data's rate noise %.4g rad/s); weighted size of the change %.4g; parts changed "
      "(cost) %.4g.</p>\n",
      best.fit.window.rmse(), design.rate_noise_rad_s, best.size_of_change,
      best.parts_changed_cost);
  if (design.commanded_torque) {
    html +=
        "<p>The TO-BE recordings are haptic playbacks: the design was fitted to the torque "
        "they commanded (the device's rendering is not in it), the inertia to their "
        "motion.</p>\n";
  }
  if (!best.held_at_as_is.empty()) {
    std::string held;
    for (const std::string& name : best.held_at_as_is) held += " " + escape(name);
    html += "<p>The design with the fewest changes: AS-IS kept for" + held +
            " (the same fit as the smallest change, which is among the alternatives).</p>\n";
  }

  html +=
      "<h2>Parameters</h2><table><tr><th>parameter</th><th>unit</th><th>AS-IS</th>"
      "<th>TO-BE</th><th>change</th><th>change %</th><th>&plusmn; uncertainty</th>"
      "<th></th></tr>\n";
  for (const DesignParameter& p : best.parameters) {
    html += std::string(changed(p) ? "<tr class=\"changed\">" : "<tr>") + "<td>" + escape(p.name) +
            "</td><td>" + escape(p.unit) + "</td><td>" + cell(p.as_is, "%.5g") + "</td><td>" +
            cell(p.to_be, "%.5g") + "</td><td>" + cell(p.change, "%+.4g") + "</td><td>" +
            cell(100 * p.relative_change, "%+.1f") + "</td><td>" + cell(p.uncertainty, "%.2g") +
            "</td><td>" + (p.free ? (p.at_bound ? "at bound" : "") : "fixed") + "</td></tr>\n";
  }
  html += "</table>\n";

  html += "<h2>What it feels like</h2>\n" + felt_table(e);
  html +=
      "<h2>Check: the models against the TO-BE recordings</h2>\n"
      "<p>Each model's hand force along the recordings' own motion, against the measured "
      "force.</p>\n" +
      check_table(e.check_before, e.check_after);
  {
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
        {"TO-BE design, opening", tobe_o.x, tobe_o.y, "#1f5fbf"},
        {"TO-BE design, closing", tobe_c.x, tobe_c.y, "#8fb0e6"},
    };
    PlotOptions options;
    options.title = "hand force against angle (mean per bin) along the TO-BE recordings' motion";
    options.x_label = "angle (deg)";
    options.y_label = "hand force (N)";
    html += inline_svg(options, series);
  }

  html += "<h2>Manufacturing tolerances</h2>\n";
  html += e.tolerances ? tolerance_section(*e.tolerances) : std::string("<p>Not analysed.</p>\n");

  html += "<h2>Alternatives</h2>\n";
  if (design.solutions.size() < 2) {
    html += "<p>No other design fits the recordings equally well.</p>\n";
  } else {
    html +=
        "<table><tr><th>#</th><th>parts (cost)</th><th>size of change</th>"
        "<th>window RMS (rad/s)</th>"
        "<th>changes</th><th>peak unlatch (N)</th><th>balance (N)</th></tr>\n";
    for (std::size_t s = 1; s < design.solutions.size(); ++s) {
      const DesignSolution& alt = design.solutions[s];
      std::string changes;
      if (!alt.held_at_as_is.empty()) {
        changes = "<em>fewest changes; AS-IS kept for";
        for (const std::string& name : alt.held_at_as_is) changes += " " + escape(name);
        changes += "</em>: ";
      }
      for (const DesignParameter& p : alt.parameters) {
        if (p.free && changed(p)) {
          changes += escape(p.name) + printf_text(" %.4g&rarr;%.4g; ", p.as_is, p.to_be);
        }
      }
      const bool have_felt = s - 1 < e.felt_alternatives.size();
      html += printf_text("<tr><td>%zu</td><td>%.4g</td><td>%.4g</td><td>%.4g</td><td>", s,
                          alt.parts_changed_cost, alt.size_of_change, alt.fit.window.rmse()) +
              changes + "</td><td>" +
              cell(have_felt ? e.felt_alternatives[s - 1].peak_unlatch_force_N : kNaN, "%.2f") +
              "</td><td>" +
              cell(have_felt ? e.felt_alternatives[s - 1].balance_force_N : kNaN, "%.2f") +
              "</td></tr>\n";
    }
    html += "</table>\n";
  }
  if (!design.notes.empty()) {
    html += "<h2>Notes</h2><ul>\n";
    for (const std::string& note : design.notes) html += "<li>" + escape(note) + "</li>\n";
    html += "</ul>\n";
  }
  return html + "</body></html>\n";
}

SpecReportFiles write_spec_report(const std::filesystem::path& dir,
                                  const InverseDesignResult& design,
                                  const SpecEvaluation& evaluation,
                                  const std::string& pdf_renderer) {
  std::error_code ignored;
  std::filesystem::create_directories(dir, ignored);
  SpecReportFiles files;
  files.json = dir / "spec.json";
  files.html = dir / "spec.html";
  // Whole or not at all, the error naming the path (acquisition/output_file.h).
  auto write = [](const std::filesystem::path& path, const std::string& text) {
    write_text_file_atomically(path, text);
  };
  write(files.json, spec_json(design, evaluation));
  write(files.html, spec_html(design, evaluation));

  std::string renderer = pdf_renderer;
  if (renderer == "none") {
    files.pdf_note = "no PDF (not asked for)";
    return files;
  }
  if (renderer.empty()) {
    if (std::system("command -v weasyprint > /dev/null 2>&1") != 0) {
      files.pdf_note = "no PDF: weasyprint is not installed (scripts/install-deps.sh installs it)";
      return files;
    }
    renderer = "weasyprint";
  }
  const std::filesystem::path pdf = dir / "spec.pdf";
  const std::filesystem::path log = dir / "spec-pdf.log";
  auto quote = [](const std::filesystem::path& path) {
    std::string out = "'";
    for (char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
  };
  const std::string command =
      renderer + " " + quote(files.html) + " " + quote(pdf) + " > " + quote(log) + " 2>&1";
  if (std::system(command.c_str()) == 0 && std::filesystem::exists(pdf)) {
    files.pdf = pdf;
    files.pdf_note = "PDF rendered by " + renderer;
    std::filesystem::remove(log, ignored);
  } else {
    files.pdf_note = "no PDF: " + renderer + " failed (see " + log.string() + ")";
  }
  return files;
}

}  // namespace doorbench
