#include "analysis/report/svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <stdexcept>

#include "acquisition/session/output_file.h"
#include "analysis/report/internal/svg_axes.h"
#include "core/html_escape.h"

namespace doorbench {
namespace {

using svg_axes::number_text;
using svg_axes::padded;
using svg_axes::Range;
using svg_axes::tick_spacing;

constexpr const char* kPalette[] = {"#1f77b4", "#d62728", "#2ca02c",
                                    "#ff7f0e", "#9467bd", "#8c564b"};

// A series' points as SVG "x,y " pairs, reduced per pixel column to its first, smallest,
// largest and last point in order (which draws the same as all of them).
template <typename ToPxX, typename ToPxY>
std::string reduced_points(const PlotSeries& s, const ToPxX& px, const ToPxY& py) {
  int column = std::numeric_limits<int>::min();
  std::vector<std::size_t> kept;
  std::size_t lowest = 0, highest = 0, first = 0, last = 0;
  auto flush = [&] {
    if (column == std::numeric_limits<int>::min()) return;
    const std::size_t picks[4] = {first, std::min(lowest, highest), std::max(lowest, highest),
                                  last};
    for (std::size_t pick : picks) {
      if (kept.empty() || kept.back() != pick) kept.push_back(pick);
    }
  };
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
    const int this_column = static_cast<int>(std::floor(px(s.x[i])));
    if (this_column != column) {
      flush();
      column = this_column;
      first = lowest = highest = i;
    }
    if (s.y[i] < s.y[lowest]) lowest = i;
    if (s.y[i] > s.y[highest]) highest = i;
    last = i;
  }
  flush();
  std::string points;
  char buffer[64];
  for (std::size_t i : kept) {
    std::snprintf(buffer, sizeof buffer, "%.1f,%.1f ", px(s.x[i]), py(s.y[i]));
    points += buffer;
  }
  return points;
}

// ' stroke="COLOUR" stroke-width=...' of a series' line, its width times width_factor. Its
// own buffer: render_svg_plot's `buffer` holds the element's start while this is called.
std::string stroke_attributes(const PlotSeries& s, const std::string& colour, double width_factor) {
  const plot_style::LineStyle style = plot_style::line_style(s.meaning);
  char attributes[128];
  std::snprintf(attributes, sizeof attributes, "stroke-width=\"%.1f\" stroke-opacity=\"%.2f\"%s",
                style.width_px * width_factor, style.opacity,
                style.dashed ? " stroke-dasharray=\"6 3\"" : "");
  return " stroke=\"" + colour + "\" " + attributes;
}

}  // namespace

std::string render_svg_plot(const PlotOptions& options, std::span<const PlotSeries> series) {
  Range x_range, y_range;
  for (const PlotSeries& s : series) {
    if (s.x.size() != s.y.size()) {
      throw std::invalid_argument("plot series '" + s.label + "': x has " +
                                  std::to_string(s.x.size()) + " values, y " +
                                  std::to_string(s.y.size()));
    }
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) {
        x_range.include(s.x[i]);
        y_range.include(s.y[i]);
      }
    }
  }
  if (!(x_range.low <= x_range.high)) {
    throw std::invalid_argument("plot '" + options.title + "' has no finite point");
  }
  x_range = padded(x_range);
  y_range = padded(y_range);

  // The legend sits right of the data area: as wide as its longest label.
  std::size_t longest_label = 0;
  for (const PlotSeries& s : series) longest_label = std::max(longest_label, s.label.size());
  const double legend_w = longest_label == 0 ? 0.0 : 44.0 + 7.0 * double(longest_label);
  const double left = 70, right = 20 + legend_w, top = 40, bottom = 55;
  const double plot_w = options.width_px - left - right;
  const double plot_h = options.height_px - top - bottom;
  auto px = [&](double x) {
    return left + (x - x_range.low) / (x_range.high - x_range.low) * plot_w;
  };
  auto py = [&](double y) {
    return top + (y_range.high - y) / (y_range.high - y_range.low) * plot_h;
  };

  std::string svg;
  char buffer[256];
  std::snprintf(buffer, sizeof buffer,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" "
                "font-family=\"sans-serif\" font-size=\"12\">\n"
                "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                options.width_px, options.height_px);
  svg += buffer;
  svg += "<text x=\"" + std::to_string(options.width_px / 2) +
         "\" y=\"22\" text-anchor=\"middle\" font-size=\"15\">" + html_escape(options.title) +
         "</text>\n";

  // Grid and ticks.
  const double x_step = tick_spacing(x_range, 8);
  for (double x = std::ceil(x_range.low / x_step) * x_step; x <= x_range.high; x += x_step) {
    std::snprintf(buffer, sizeof buffer,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">",
                  px(x), top, px(x), top + plot_h, px(x), top + plot_h + 16);
    svg += buffer + number_text(x, x_step) + "</text>\n";
  }
  const double y_step = tick_spacing(y_range, 6);
  for (double y = std::ceil(y_range.low / y_step) * y_step; y <= y_range.high; y += y_step) {
    std::snprintf(buffer, sizeof buffer,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">",
                  left, py(y), left + plot_w, py(y), left - 6, py(y) + 4);
    svg += buffer + number_text(y, y_step) + "</text>\n";
  }
  std::snprintf(buffer, sizeof buffer,
                "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
                "stroke=\"#444\"/>\n",
                left, top, plot_w, plot_h);
  svg += buffer;
  svg += "<text x=\"" + std::to_string(static_cast<int>(left + plot_w / 2)) + "\" y=\"" +
         std::to_string(options.height_px - 12) + "\" text-anchor=\"middle\">" +
         html_escape(options.x_label) + "</text>\n";
  std::snprintf(buffer, sizeof buffer,
                "<text transform=\"translate(16 %.1f) rotate(-90)\" text-anchor=\"middle\">",
                top + plot_h / 2);
  svg += buffer + html_escape(options.y_label) + "</text>\n";

  // Series in stacking order (plot_style: measured on top), each reduced per pixel column:
  // first, smallest, largest and last point in order.
  std::vector<std::size_t> order(series.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) {
    return plot_style::line_style(series[i].meaning).layer <
           plot_style::line_style(series[j].meaning).layer;
  });
  auto colour_of = [&](std::size_t index) {
    const PlotSeries& s = series[index];
    if (!s.color.empty()) return s.color;
    if (s.meaning != plot_style::Meaning::kOther) return plot_style::hex_colour(s.meaning);
    return std::string(kPalette[index % 6]);
  };
  // A labelled series' line carries its label as <title> (a tooltip; the legend's key).
  for (std::size_t index : order) {
    const PlotSeries& s = series[index];
    svg += "<polyline fill=\"none\"" + stroke_attributes(s, colour_of(index), 1.0) + " points=\"";
    svg += reduced_points(s, px, py);
    svg +=
        s.label.empty() ? "\"/>\n" : "\"><title>" + html_escape(s.label) + "</title></polyline>\n";
  }
  // The legend, right of the data area, in the order the series were given.
  int legend_entries = 0;
  const double legend_x = left + plot_w + 16;
  for (std::size_t index = 0; index < series.size(); ++index) {
    if (series[index].label.empty()) continue;  // unlabelled series share a labelled entry
    const double row_y = top + 8 + 18.0 * double(legend_entries++);
    std::snprintf(buffer, sizeof buffer, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"",
                  legend_x, row_y, legend_x + 24, row_y);
    svg += buffer;
    svg += stroke_attributes(series[index], colour_of(index), 2.0) + "/>";
    std::snprintf(buffer, sizeof buffer, "<text x=\"%.1f\" y=\"%.1f\">", legend_x + 30, row_y + 4);
    svg += buffer + html_escape(series[index].label) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

void write_svg_plot(const std::string& path, const PlotOptions& options,
                    std::span<const PlotSeries> series) {
  write_text_file_atomically(path, render_svg_plot(options, series));
}

}  // namespace doorbench
