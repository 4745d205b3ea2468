// One plotting vocabulary (analysis/report/plot_style.h) in the SVG reports: measured drawn after
// (on top of) the model's curve, the model dashed, the legend outside the data area, a
// colour per meaning the same as the viewer's.
#include <catch2/catch.hpp>
#include <regex>
#include <string>
#include <vector>

#include "analysis/report/plot_style.h"
#include "analysis/report/svg_plot.h"
#include "viewer/plot_view.h"
#include "viewer/session_data.h"

using namespace doorbench;
using plot_style::Meaning;

TEST_CASE("SVG plots draw measured on top of a dashed model curve, legend beside the data",
          "[plot_style]") {
  const std::vector<double> x = {0.0, 1.0, 2.0, 3.0}, y = {0.0, 1.0, 0.5, 2.0};
  // Given simulated-first or measured-first, measured is drawn last.
  for (bool measured_first : {true, false}) {
    std::vector<PlotSeries> series;
    const PlotSeries measured{"measured", x, y, "", Meaning::kMeasured};
    const PlotSeries simulated{"simulated", x, y, "", Meaning::kSimulated};
    if (measured_first)
      series = {measured, simulated};
    else
      series = {simulated, measured};
    const std::string svg = render_svg_plot({"rate", "time [s]", "rate [deg/s]"}, series);
    const std::string measured_stroke = "stroke=\"" + plot_style::hex_colour(Meaning::kMeasured);
    const std::string simulated_stroke = "stroke=\"" + plot_style::hex_colour(Meaning::kSimulated);
    const std::size_t measured_line = svg.find("<polyline fill=\"none\" " + measured_stroke);
    const std::size_t simulated_line = svg.find("<polyline fill=\"none\" " + simulated_stroke);
    REQUIRE(measured_line != std::string::npos);
    REQUIRE(simulated_line != std::string::npos);
    CHECK(simulated_line < measured_line);
    // The model dashed, measured solid.
    const std::string simulated_tag =
        svg.substr(simulated_line, svg.find('>', simulated_line) - simulated_line);
    const std::string measured_tag =
        svg.substr(measured_line, svg.find('>', measured_line) - measured_line);
    CHECK(simulated_tag.find("stroke-dasharray") != std::string::npos);
    CHECK(measured_tag.find("stroke-dasharray") == std::string::npos);
    // Legend texts right of the data frame's right edge.
    const std::regex frame("<rect x=\"([0-9.]+)\" y=\"[0-9.]+\" width=\"([0-9.]+)\"");
    std::smatch m;
    REQUIRE(std::regex_search(svg, m, frame));
    const double right_edge = std::stod(m[1]) + std::stod(m[2]);
    for (const char* label : {"measured</text>", "simulated</text>"}) {
      const std::size_t at = svg.find(label);
      REQUIRE(at != std::string::npos);
      const std::size_t text = svg.rfind("<text x=\"", at);
      const double text_x = std::stod(svg.substr(text + 9));
      INFO(label << " at x " << text_x << ", data area ends at " << right_edge);
      CHECK(text_x > right_edge);
    }
  }
}

TEST_CASE("the viewer takes its colours per meaning from the same vocabulary", "[plot_style]") {
  for (Meaning meaning : {Meaning::kMeasured, Meaning::kSimulated, Meaning::kOpening,
                          Meaning::kClosing, Meaning::kResidual}) {
    const viewer::Rgba c = viewer::meaning_colour(meaning, true);
    char hex[8];
    std::snprintf(hex, sizeof hex, "#%02x%02x%02x", unsigned(c.r), unsigned(c.g), unsigned(c.b));
    CHECK(plot_style::hex_colour(meaning) == hex);
  }
  // Distinct colours for distinct meanings.
  const std::vector<Meaning> all = {Meaning::kMeasured, Meaning::kSimulated, Meaning::kTuned,
                                    Meaning::kOpening,  Meaning::kClosing,   Meaning::kResidual};
  for (std::size_t i = 0; i < all.size(); ++i) {
    for (std::size_t j = i + 1; j < all.size(); ++j) {
      CHECK(plot_style::hex_colour(all[i]) != plot_style::hex_colour(all[j]));
    }
  }
  CHECK(plot_style::axis_label("angle", "deg") == "angle [deg]");
  CHECK(plot_style::display_unit("rad/s").unit == "deg/s");
}

TEST_CASE("viewer ticks: integer axes, at least two ticks, tiny steps with an exponent",
          "[viewer][plot_style]") {
  using doorbench::viewer::nice_ticks;
  using doorbench::viewer::tick_label;
  // The loop's steps 0..3: whole numbers only, however many ticks are asked for.
  CHECK(nice_ticks(-0.1, 3.1, 12, 1.0) == std::vector<double>{0, 1, 2, 3});
  CHECK(nice_ticks(-0.1, 3.1, 12).size() > 4);  // without: fractional steps
  // A narrow range that one tick of the first try would fall in gets two or more.
  const auto narrow = nice_ticks(0.1003, 0.1011, 1);  // a first try of step 1e-3: one tick
  CHECK(narrow.size() >= 2);
  for (double t : narrow) CHECK((t >= 0.1003 && t <= 0.1011));
  // A device's micrometre-scale channel: "5e-06", not "0.000005".
  CHECK(tick_label(5e-6, 1e-6) == "5e-06");
  CHECK(tick_label(0.0, 1e-6) == "0");
  CHECK(tick_label(0.25, 0.05) == "0.25");
}
