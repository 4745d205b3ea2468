// global-search.svg of `doorbench fit` (app/fit_output.h): each free parameter's place within
// its bounds on the global stage's scale (analysis/fit/search_scale.h), the fit's value and the
// ranges of the distinct optima, from a summary made here with known places.
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "analysis/fit/search_scale.h"
#include "app/fit_output.h"
#include "fixtures/temp_dir.h"
#include "tests/support/files.h"
#include "tests/support/svg_check.h"

namespace doorbench {
namespace {

FittedParameter free_parameter(const std::string& name, Bounds bounds) {
  FittedParameter parameter;
  parameter.name = name;
  parameter.free = true;
  parameter.bounds = bounds;
  return parameter;
}

// Two free parameters: k_lock on [0, 2e4] N*m/rad (logarithmic: [20, 2e4]) and J on
// [0.1, 5] kg*m^2 (linear); the fit at the middle of each scale, a second optimum 0.5 % above
// it in cost with k_lock at its scale's lower end, a third 50 % above with k_lock at its upper
// bound and J at its lower.
FitSummary summary_with_three_optima() {
  FitSummary summary;
  summary.parameters = {free_parameter("J", {0.1, 5.0}), free_parameter("k", {0.0, 500.0}),
                        free_parameter("k_lock", {0.0, 2e4})};
  summary.parameters[1].free = false;
  summary.free_names = {"k_lock", "J"};
  summary.global.ran = true;
  const double middle_k_lock = std::sqrt(20.0 * 2e4);
  summary.global.optima = {{100.0, 80.0, {"the data-derived start"}, {middle_k_lock, 2.55}},
                           {100.5, 80.0, {"the start as given"}, {20.0, 2.55}},
                           {150.0, 70.0, {"sample point 3"}, {2e4, 0.1}}};
  return summary;
}

}  // namespace

TEST_CASE("global search plot: the stage's scale of a parameter's bounds", "[fit][plots]") {
  // Over two decades from 0: logarithmic, from the upper bound / 1000.
  const Bounds stiffness{0.0, 2e4};
  CHECK(search_scale_is_logarithmic(stiffness));
  CHECK(search_scale_place(stiffness, 20.0) == Approx(0.0).margin(1e-12));
  CHECK(search_scale_place(stiffness, 2e4) == Approx(1.0));
  CHECK(search_scale_place(stiffness, std::sqrt(20.0 * 2e4)) == Approx(0.5));
  CHECK(search_scale_place(stiffness, 5.0) == 0.0);  // below the scale's lower end
  const Bounds inertia{0.1, 5.0};
  CHECK_FALSE(search_scale_is_logarithmic(inertia));
  CHECK(search_scale_place(inertia, 2.55) == Approx(0.5));
  CHECK(search_scale_place(inertia, 7.0) == 1.0);
  // Exactly two decades: linear.
  CHECK_FALSE(search_scale_is_logarithmic({0.0005, 0.05}));
}

TEST_CASE("global search plot: a row per free parameter, the fit and the optima's ranges",
          "[fit][plots]") {
  const std::vector<ForestRow> rows = app::global_search_rows(summary_with_three_optima());
  REQUIRE(rows.size() == 2);
  CHECK(rows[0].label == "k_lock (log)");
  CHECK(rows[0].estimate == Approx(0.5));
  CHECK(rows[0].low == Approx(0.0).margin(1e-12));
  CHECK(rows[0].high == Approx(1.0));
  // Within 1 % of the fit's cost: the fit and the second optimum.
  CHECK(rows[0].inner_low == Approx(0.0).margin(1e-12));
  CHECK(rows[0].inner_high == Approx(0.5));
  CHECK(rows[1].label == "J");
  CHECK(rows[1].estimate == Approx(0.5));
  CHECK(rows[1].low == Approx(0.0).margin(1e-12));
  CHECK(rows[1].high == Approx(0.5));
  CHECK(rows[1].inner_low == Approx(0.5));
  CHECK(rows[1].inner_high == Approx(0.5));
}

TEST_CASE("global search plot: no inner range when only the fit is within 1 % of its cost",
          "[fit][plots]") {
  FitSummary summary = summary_with_three_optima();
  summary.global.optima[1].cost = 101.5;
  const std::vector<ForestRow> rows = app::global_search_rows(summary);
  REQUIRE(rows.size() == 2);
  CHECK(std::isnan(rows[0].inner_low));
  CHECK(std::isnan(rows[0].inner_high));
  CHECK(rows[0].low == Approx(0.0).margin(1e-12));
}

TEST_CASE("global search plot: written as SVG with more than one optimum, not otherwise",
          "[fit][plots]") {
  const testing::TempDir dir("global_search_plot");
  const FitSummary summary = summary_with_three_optima();
  REQUIRE(app::write_global_search_plot(dir.path, summary) == "global-search.svg");
  const std::string svg = testing::read_file(dir.path / "global-search.svg");
  CHECK(svg.find("Global search: the fit and 2 other distinct optima, each free parameter "
                 "within its bounds") != std::string::npos);
  CHECK(svg.find("k_lock (log)") != std::string::npos);
  CHECK(svg.find("range of the 3 distinct optima") != std::string::npos);
  CHECK(svg.find("range of those within 1 % of the fit&#39;s cost") != std::string::npos);
  const testing::SvgCheck check = testing::check_svgs({dir.path / "global-search.svg"});
  INFO(check.output);
  CHECK(check.status == 0);
  CHECK(check.svgs == 1);

  FitSummary one = summary;
  one.global.optima.resize(1);
  const testing::TempDir empty("global_search_plot_one");
  CHECK(app::global_search_rows(one).empty());
  CHECK(app::write_global_search_plot(empty.path, one).empty());
  CHECK_FALSE(std::filesystem::exists(empty.path / "global-search.svg"));
  FitSummary none = summary;
  none.global.ran = false;
  CHECK(app::global_search_rows(none).empty());
}

}  // namespace doorbench
