#include "calibration/certificate.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "calibration/procedure.h"
#include "core/html_escape.h"
#include "core/number_format.h"

namespace doorbench::calibration {

namespace {

std::string number(double value) {
  return value == 0 ? "0" : format_significant(value, 6);
}

std::string row(const std::string& name, const std::string& value) {
  return "<tr><th>" + html_escape(name) + "</th><td>" + html_escape(value) + "</td></tr>\n";
}

// Residual against reference, loading and unloading apart, with a zero line.
std::string residual_plot(const CalibrationRecord& r) {
  const double width = 640, height = 300, left = 70, right = 20, top = 20, bottom = 45;
  double x0 = INFINITY, x1 = -INFINITY, y_max = 0.0;
  for (const CalibrationPoint& p : r.points) {
    x0 = std::min(x0, p.reference);
    x1 = std::max(x1, p.reference);
    y_max = std::max(y_max, std::abs(p.residual));
  }
  if (!(x1 > x0)) {
    x0 -= 1;
    x1 += 1;
  }
  if (y_max == 0) y_max = 1;
  y_max *= 1.15;
  auto sx = [&](double x) { return left + (x - x0) / (x1 - x0) * (width - left - right); };
  auto sy = [&](double y) { return top + (y_max - y) / (2 * y_max) * (height - top - bottom); };
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + number(width) +
                    "\" height=\"" + number(height) +
                    "\" font-family=\"sans-serif\" font-size=\"12\">\n";
  svg += "<rect x=\"" + number(left) + "\" y=\"" + number(top) + "\" width=\"" +
         number(width - left - right) + "\" height=\"" + number(height - top - bottom) +
         "\" fill=\"none\" stroke=\"#888\"/>\n";
  svg += "<line x1=\"" + number(left) + "\" x2=\"" + number(width - right) + "\" y1=\"" +
         number(sy(0)) + "\" y2=\"" + number(sy(0)) +
         "\" stroke=\"#888\" stroke-dasharray=\"4 3\"/>\n";
  const double u = r.standard_uncertainty;
  if (u > 0 && 2 * u < y_max) {
    for (double band : {2 * u, -2 * u}) {
      svg += "<line x1=\"" + number(left) + "\" x2=\"" + number(width - right) + "\" y1=\"" +
             number(sy(band)) + "\" y2=\"" + number(sy(band)) +
             "\" stroke=\"#c60\" stroke-dasharray=\"2 4\"/>\n";
    }
  }
  for (const CalibrationPoint& p : r.points) {
    const bool unloading = p.branch == "unloading";
    svg += std::string("<circle cx=\"") + number(sx(p.reference)) + "\" cy=\"" +
           number(sy(p.residual)) + "\" r=\"4\" fill=\"" + (unloading ? "none" : "#1f5fa8") +
           "\" stroke=\"#1f5fa8\"/>\n";
  }
  for (double x : {x0, x1}) {
    svg += "<text x=\"" + number(sx(x)) + "\" y=\"" + number(height - bottom + 16) +
           "\" text-anchor=\"middle\">" + number(x) + "</text>\n";
  }
  for (double y : {-y_max, 0.0, y_max}) {
    svg += "<text x=\"" + number(left - 6) + "\" y=\"" + number(sy(y) + 4) +
           "\" text-anchor=\"end\">" + number(y) + "</text>\n";
  }
  svg += "<text x=\"" + number((left + width - right) / 2) + "\" y=\"" + number(height - 8) +
         "\" text-anchor=\"middle\">reference (" + html_escape(r.unit) +
         "); filled: loading or no direction, open: unloading; dotted: ±2u</text>\n";
  svg += "<text x=\"14\" y=\"" + number(top + (height - top - bottom) / 2) +
         "\" transform=\"rotate(-90 14 " + number(top + (height - top - bottom) / 2) +
         ")\" text-anchor=\"middle\">residual (" + html_escape(r.unit) + ")</text>\n";
  return svg + "</svg>\n";
}

}  // namespace

std::string certificate_html(const CalibrationRecord& r) {
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>Calibration "
      "certificate " +
      html_escape(r.id) +
      "</title>\n<style>body{font-family:sans-serif;max-width:60em;margin:2em auto}"
      "table{border-collapse:collapse;margin:0.5em 0 1.5em}th,td{border:1px solid #bbb;"
      "padding:0.25em 0.6em;text-align:left}td.n{text-align:right;font-family:monospace}"
      "</style></head><body>\n";
  html += "<h1>Calibration certificate</h1>\n<p>doorbench calibration record <b>" +
          html_escape(r.id) + "</b></p>\n<table>\n";
  html += row("sensor", r.sensor_kind + " " + r.sensor_serial);
  html += row("version", std::to_string(r.version) +
                             (r.supersedes.empty() ? "" : " (supersedes " + r.supersedes + ")"));
  html += row("date (UTC)", r.date_utc);
  html += row("operator", r.operator_name);
  html += row("valid until", r.valid_until_utc.empty() ? "no expiry stated" : r.valid_until_utc);
  std::string range = "not stated";
  if (std::isfinite(r.valid_min) || std::isfinite(r.valid_max)) {
    range = number(r.valid_min) + " to " + number(r.valid_max) + " " + r.unit;
  }
  html += row("valid range", range);
  html += row("method", r.method);
  html += row("references", r.references);
  if (!r.notes.empty()) html += row("notes", r.notes);
  html += "</table>\n<h2>Result</h2>\n<p>" + html_escape(r.unit) + " = ";
  for (std::size_t k = 0; k < r.coefficients.size(); ++k) {
    html += (k ? " + " : "") + number(r.coefficients[k]) +
            (k == 0   ? ""
             : k == 1 ? " · x"
                      : " · x<sup>" + std::to_string(k) + "</sup>");
  }
  html += " &nbsp; (x: the signal in " + html_escape(r.input_unit) + ")";
  if (r.delay_s != 0) {
    html += "; the channel lags by " + number(r.delay_s * 1e3) + " ms ± " +
            number(r.delay_standard_uncertainty_s * 1e3) + " ms, corrected on read";
  }
  html += "</p>\n";
  if (!r.quantities.empty()) {
    html +=
        "<table>\n<tr><th>quantity</th><th>value</th><th>standard "
        "uncertainty</th><th>unit</th></tr>\n";
    for (const CalibrationQuantity& q : r.quantities) {
      html += "<tr><td>" + html_escape(q.name) + "</td><td class=\"n\">" + number(q.value) +
              "</td><td class=\"n\">" +
              (q.standard_uncertainty > 0 ? number(q.standard_uncertainty) : "") + "</td><td>" +
              html_escape(q.unit) + "</td></tr>\n";
    }
    html += "</table>\n";
  }
  if (!r.points.empty()) {
    html += "<h2>Reference points</h2>\n<table>\n<tr><th>#</th><th>reference (" +
            html_escape(r.unit) + ")</th><th>branch</th><th>signal (" + html_escape(r.input_unit) +
            ")</th><th>sd (" + html_escape(r.input_unit) + ")</th><th>samples</th><th>residual (" +
            html_escape(r.unit) + ")</th></tr>\n";
    for (std::size_t i = 0; i < r.points.size(); ++i) {
      const CalibrationPoint& p = r.points[i];
      html += "<tr><td>" + std::to_string(i + 1) + "</td><td class=\"n\">" + number(p.reference) +
              "</td><td>" + html_escape(p.branch) + "</td><td class=\"n\">" + number(p.signal) +
              "</td><td class=\"n\">" + number(p.signal_std) + "</td><td class=\"n\">" +
              std::to_string(p.samples) + "</td><td class=\"n\">" + number(p.residual) +
              "</td></tr>\n";
    }
    html += "</table>\n<h2>Residuals</h2>\n" + residual_plot(r);
  }
  html += "<h2>Uncertainty</h2>\n<p>Standard uncertainty of a calibrated value: <b>" +
          number(r.standard_uncertainty) + " " + html_escape(r.unit) +
          "</b> (coverage factor k = 1). The expanded uncertainty U = 2u covers about 95 %: "
          "uncertainties estimated from few points are scaled by t<sub>95</sub>(ν)/1.96 "
          "(docs/calibration.md). It does not include the noise of a single sample.</p>\n";
  html += "</body></html>\n";
  return html;
}

void write_certificate(const std::filesystem::path& path, const CalibrationRecord& record) {
  write_text_file_atomically(path, certificate_html(record));  // whole or not at all
}

}  // namespace doorbench::calibration
