#include "analysis/report/svg_charts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "analysis/report/internal/svg_axes.h"
#include "core/html_escape.h"
#include "core/number_format.h"

namespace doorbench {
namespace {

using svg_axes::Range;

constexpr const char* kIntervalColour = "#1f77d6";
constexpr const char* kInnerColour = "#e6550d";
constexpr const char* kEstimateColour = "#000000";
constexpr const char* kBandColour = "#2ca02c";
constexpr const char* kPointColour = "#1f77d6";
constexpr const char* kCurveColour = "#e6550d";
constexpr double kCharWidthPx = 7.0;  // a 12 px sans-serif character, generously

std::string svg_open(int width, int height, const std::string& title) {
  std::string svg = printf_text(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      width, height);
  svg +=
      printf_text("<text x=\"%d\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">", width / 2) +
      html_escape(title) + "</text>\n";
  return svg;
}

// One legend entry right of the data area: its key (a line in the series' colour and
// width) and its text.
std::string legend_entry(double x, double y, const std::string& colour, double width,
                         double opacity, const std::string& label) {
  return printf_text(
             "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
             "stroke-width=\"%.1f\" stroke-opacity=\"%.2f\"/>",
             x, y, x + 24, y, colour.c_str(), width, opacity) +
         printf_text("<text x=\"%.1f\" y=\"%.1f\">", x + 30, y + 4) + html_escape(label) +
         "</text>\n";
}

double legend_width(const std::vector<std::string>& labels) {
  std::size_t longest = 0;
  for (const std::string& label : labels) longest = std::max(longest, label.size());
  return longest == 0 ? 0.0 : 44.0 + kCharWidthPx * double(longest);
}

// The x axis' ticks and grid lines over the data area, and its label.
std::string x_axis(const Range& range, double left, double top, double width, double height,
                   int svg_height, const std::string& label) {
  std::string svg;
  const double step = svg_axes::tick_spacing(range, 6);
  const auto px = [&](double x) {
    return left + (x - range.low) / (range.high - range.low) * width;
  };
  for (double x = std::ceil(range.low / step) * step; x <= range.high; x += step) {
    svg += printf_text(
               "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
               "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">",
               px(x), top, px(x), top + height, px(x), top + height + 16) +
           svg_axes::number_text(x, step) + "</text>\n";
  }
  svg += printf_text("<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">", left + width / 2,
                     svg_height - 12) +
         html_escape(label) + "</text>\n";
  return svg;
}

struct ForestGeometry {
  Range range;
  double left = 0, top = 40, width = 0, row_height = 24, height = 0;
  double px(double x) const {
    return left +
           (std::clamp(x, range.low, range.high) - range.low) / (range.high - range.low) * width;
  }
  double row_y(std::size_t row) const { return top + row_height * (double(row) + 0.5); }
};

Range forest_range(const ForestOptions& options, std::span<const ForestRow> rows) {
  Range range;
  for (const ForestRow& row : rows) {
    for (double value : {row.estimate, row.low, row.high, row.inner_low, row.inner_high})
      range.include(value);
  }
  if (range.empty())
    throw std::invalid_argument("forest plot '" + options.title + "': nothing finite to draw");
  range.include(options.reference_line);
  range.include(options.band_low);
  range.include(options.band_high);
  return svg_axes::padded(range);
}

// A row's note where it does not cover the row's marks: right of them when it fits, else
// left of them, else against the data area's right edge.
std::string forest_note(const ForestGeometry& g, const ForestRow& row, double y) {
  double first = g.left + g.width, last = g.left;  // the marks' extent, pixels
  for (const double value : {row.estimate, row.low, row.high, row.inner_low, row.inner_high}) {
    if (std::isnan(value)) continue;
    first = std::min(first, g.px(value) - 6);
    last = std::max(last, g.px(value) + 6);
  }
  if (first > last) first = last = g.left;               // no marks
  const double text_px = 6.0 * double(row.note.size());  // 11 px text, generously
  const char* right_anchor = " text-anchor=\"end\"";
  double x = last + 6;
  const char* anchor = "";
  if (x + text_px > g.left + g.width - 4) {
    x = first - 6 >= g.left + 4 + text_px ? first - 6 : g.left + g.width - 4;
    anchor = right_anchor;
  }
  return printf_text("<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" fill=\"#444\"%s>", x, y + 4,
                     anchor) +
         html_escape(row.note) + "</text>\n";
}

// One row: its label, interval (with caps, or an arrow at an open end), inner interval,
// estimate and note.
std::string forest_row(const ForestOptions& options, const ForestGeometry& g, std::size_t index,
                       const ForestRow& row) {
  const double y = g.row_y(index);
  std::string svg;
  if (index % 2 == 1)
    svg += printf_text(
        "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#f4f4f4\"/>\n", g.left,
        y - g.row_height / 2, g.width, g.row_height);
  svg += printf_text("<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">", g.left - 8, y + 4) +
         html_escape(row.label) + "</text>\n";
  const bool has_interval = !std::isnan(row.low) && !std::isnan(row.high);
  if (has_interval) {
    const double x1 = g.px(row.low), x2 = g.px(row.high);
    std::string points = printf_text("%.1f,%.1f %.1f,%.1f ", x1, y, x2, y);
    if (std::isfinite(row.low))
      points = printf_text("%.1f,%.1f %.1f,%.1f ", x1, y - 5, x1, y + 5) + points;
    if (std::isfinite(row.high)) points += printf_text("%.1f,%.1f %.1f,%.1f", x2, y - 5, x2, y + 5);
    svg += "<polyline fill=\"none\" stroke=\"" + std::string(kIntervalColour) +
           "\" stroke-width=\"1.6\" points=\"" + points + "\"><title>" +
           html_escape(options.interval_label) + "</title></polyline>\n";
    for (const double end : {row.low, row.high}) {
      if (std::isfinite(end)) continue;
      const double tip = end > 0 ? g.left + g.width : g.left, back = end > 0 ? -8.0 : 8.0;
      svg += printf_text(
          "<polyline fill=\"%s\" stroke=\"%s\" points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f\"/>\n",
          kIntervalColour, kIntervalColour, tip + back, y - 4, tip, y, tip + back, y + 4);
    }
  }
  if (std::isfinite(row.inner_low) && std::isfinite(row.inner_high)) {
    svg += printf_text(
               "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"6.0\" "
               "stroke-opacity=\"0.55\" points=\"%.1f,%.1f %.1f,%.1f\"><title>",
               kInnerColour, g.px(row.inner_low), y, g.px(row.inner_high), y) +
           html_escape(options.inner_label) + "</title></polyline>\n";
  }
  if (std::isfinite(row.estimate)) {
    const double x = g.px(row.estimate);
    svg += printf_text(
               "<polyline fill=\"%s\" stroke=\"%s\" points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f "
               "%.1f,%.1f %.1f,%.1f\"><title>",
               kEstimateColour, kEstimateColour, x - 5, y, x, y - 5, x + 5, y, x, y + 5, x - 5, y) +
           html_escape(options.estimate_label) + "</title></polyline>\n";
  }
  if (!row.note.empty()) svg += forest_note(g, row, y);
  return svg;
}

}  // namespace

std::string render_svg_forest(const ForestOptions& options, std::span<const ForestRow> rows) {
  ForestGeometry g;
  g.range = forest_range(options, rows);
  std::size_t longest = 0;
  for (const ForestRow& row : rows) longest = std::max(longest, row.label.size());
  g.left = std::clamp(20.0 + kCharWidthPx * double(longest), 60.0, 320.0);
  bool has_inner = false;
  for (const ForestRow& row : rows) has_inner = has_inner || std::isfinite(row.inner_low);
  std::vector<std::string> legend{options.interval_label, options.estimate_label};
  if (has_inner) legend.push_back(options.inner_label);
  const bool has_band = std::isfinite(options.band_low) && std::isfinite(options.band_high);
  if (has_band) legend.push_back(options.band_label);
  const double legend_w = legend_width(legend);
  g.width = std::max(200.0, options.width_px - g.left - 20 - legend_w);
  g.height = std::max(g.row_height * double(rows.size()), 18.0 * double(legend.size()) + 16);
  const int height = static_cast<int>(g.top + g.height + 50);
  const int width = static_cast<int>(g.left + g.width + 20 + legend_w);

  std::string svg = svg_open(width, height, options.title);
  if (has_band) {
    const double x1 = g.px(options.band_low), x2 = g.px(options.band_high);
    svg += printf_text(
               "<polyline fill=\"%s\" fill-opacity=\"0.15\" stroke=\"%s\" "
               "stroke-opacity=\"0\" points=\"%.1f,%.1f %.1f,%.1f %.1f,%.1f %.1f,%.1f\"><title>",
               kBandColour, kBandColour, x1, g.top, x2, g.top, x2, g.top + g.height, x1,
               g.top + g.height) +
           html_escape(options.band_label) + "</title></polyline>\n";
  }
  svg += x_axis(g.range, g.left, g.top, g.width, g.height, height, options.x_label);
  for (std::size_t r = 0; r < rows.size(); ++r) svg += forest_row(options, g, r, rows[r]);
  if (std::isfinite(options.reference_line)) {
    const double x = g.px(options.reference_line);
    svg += printf_text(
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#666\" "
        "stroke-dasharray=\"4 3\"/>\n",
        x, g.top, x, g.top + g.height);
  }
  svg += printf_text(
      "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
      "stroke=\"#444\"/>\n",
      g.left, g.top, g.width, g.height);
  const double legend_x = g.left + g.width + 16;
  double legend_y = g.top + 8;
  svg += legend_entry(legend_x, legend_y, kIntervalColour, 1.6, 1.0, options.interval_label);
  svg += legend_entry(legend_x, legend_y += 18, kEstimateColour, 4.0, 1.0, options.estimate_label);
  if (has_inner)
    svg += legend_entry(legend_x, legend_y += 18, kInnerColour, 6.0, 0.55, options.inner_label);
  if (has_band)
    svg += legend_entry(legend_x, legend_y += 18, kBandColour, 8.0, 0.3, options.band_label);
  return svg + "</svg>\n";
}

namespace {

std::string dose_points(const DoseResponsePlot& plot, const auto& px, const auto& py) {
  double heaviest = 0;
  for (double w : plot.weight) heaviest = std::max(heaviest, w);
  std::string svg = "<g fill=\"" + std::string(kPointColour) +
                    "\" fill-opacity=\"0.55\" stroke=\"" + kPointColour + "\"><title>" +
                    html_escape(plot.points_label) + "</title>";
  for (std::size_t i = 0; i < plot.x.size(); ++i) {
    if (!std::isfinite(plot.x[i]) || !std::isfinite(plot.y[i])) continue;
    // Area proportional to the weight: the heaviest point 9 px in radius.
    const double radius =
        heaviest > 0 ? 9.0 * std::sqrt(std::max(0.0, plot.weight[i]) / heaviest) : 4.0;
    svg += printf_text("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\"/>", px(plot.x[i]), py(plot.y[i]),
                       std::max(radius, 1.5));
  }
  return svg + "</g>\n";
}

}  // namespace

std::string render_svg_dose_response(const DoseResponsePlot& plot) {
  if (plot.x.size() != plot.y.size() || plot.x.size() != plot.weight.size() ||
      plot.curve_x.size() != plot.curve_y.size() ||
      (!plot.band_low.empty() && (plot.band_low.size() != plot.curve_x.size() ||
                                  plot.band_high.size() != plot.curve_x.size())))
    throw std::invalid_argument("dose-response plot '" + plot.title +
                                "': series of different lengths");
  Range x_range;
  for (double x : plot.x) x_range.include(x);
  for (double x : plot.curve_x) x_range.include(x);
  if (x_range.empty())
    throw std::invalid_argument("dose-response plot '" + plot.title + "': no finite point");
  x_range = svg_axes::padded(x_range);
  const Range y_range{plot.y_min - 0.02 * (plot.y_max - plot.y_min),
                      plot.y_max + 0.02 * (plot.y_max - plot.y_min)};
  std::vector<std::string> legend{plot.points_label, plot.curve_label};
  if (!plot.band_low.empty()) legend.push_back(plot.band_label);
  const double legend_w = legend_width(legend);
  const double left = 70, top = 40;
  const double width = plot.width_px - left - 20 - legend_w, height = plot.height_px - top - 55.0;
  const auto px = [&](double x) {
    return left + (x - x_range.low) / (x_range.high - x_range.low) * width;
  };
  const auto py = [&](double y) {
    return top + (y_range.high - y) / (y_range.high - y_range.low) * height;
  };

  std::string svg = svg_open(plot.width_px, plot.height_px, plot.title);
  svg += x_axis(x_range, left, top, width, height, plot.height_px, plot.x_label);
  const double y_step = svg_axes::tick_spacing(y_range, 5);
  for (double y = std::ceil(y_range.low / y_step) * y_step; y <= y_range.high; y += y_step) {
    svg += printf_text(
               "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
               "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">",
               left, py(y), left + width, py(y), left - 6, py(y) + 4) +
           svg_axes::number_text(y, y_step) + "</text>\n";
  }
  svg += printf_text("<text transform=\"translate(16 %.1f) rotate(-90)\" text-anchor=\"middle\">",
                     top + height / 2) +
         html_escape(plot.y_label) + "</text>\n";
  if (!plot.band_low.empty()) {
    std::string points;
    for (std::size_t i = 0; i < plot.curve_x.size(); ++i)
      points += printf_text("%.1f,%.1f ", px(plot.curve_x[i]), py(plot.band_high[i]));
    for (std::size_t i = plot.curve_x.size(); i-- > 0;)
      points += printf_text("%.1f,%.1f ", px(plot.curve_x[i]), py(plot.band_low[i]));
    svg += "<polygon fill=\"" + std::string(kCurveColour) + "\" fill-opacity=\"0.18\" stroke=\"" +
           kCurveColour + "\" stroke-opacity=\"0\" points=\"" + points + "\"><title>" +
           html_escape(plot.band_label) + "</title></polygon>\n";
  }
  std::string curve;
  for (std::size_t i = 0; i < plot.curve_x.size(); ++i)
    curve += printf_text("%.1f,%.1f ", px(plot.curve_x[i]), py(plot.curve_y[i]));
  svg += "<polyline fill=\"none\" stroke=\"" + std::string(kCurveColour) +
         "\" stroke-width=\"1.8\" points=\"" + curve + "\"><title>" +
         html_escape(plot.curve_label) + "</title></polyline>\n";
  svg += dose_points(plot, px, py);
  svg += printf_text(
      "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
      "stroke=\"#444\"/>\n",
      left, top, width, height);
  const double legend_x = left + width + 16;
  svg += legend_entry(legend_x, top + 8, kPointColour, 6.0, 0.55, plot.points_label);
  svg += legend_entry(legend_x, top + 26, kCurveColour, 1.8, 1.0, plot.curve_label);
  if (!plot.band_low.empty())
    svg += legend_entry(legend_x, top + 44, kCurveColour, 8.0, 0.18, plot.band_label);
  return svg + "</svg>\n";
}

}  // namespace doorbench
