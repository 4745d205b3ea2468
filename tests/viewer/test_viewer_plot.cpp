// The viewer's plot model: decimation keeps each pixel column's min and max exactly, zoom
// keeps the point under the cursor, linked time axes follow each other, crosshair readout.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <random>

#include "fixtures/temp_dir.h"
#include "viewer/loop_steps.h"
#include "viewer/plot_series.h"
#include "viewer/plot_view.h"

using namespace doorbench::viewer;
using Catch::Matchers::Contains;

namespace {

// The brute force decimate() must agree with: every sample's column from its x directly.
std::vector<Column> brute_force(const Series& s, double x_min, double x_max, std::size_t width) {
  std::vector<Column> columns(width);
  const double span = x_max - x_min;
  auto edge = [&](std::size_t c) { return x_min + span * (double(c) / double(width)); };
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double x = s.x(i);
    if (x < x_min || x > x_max) continue;
    std::size_t c = 0;
    while (c + 1 < width && x >= edge(c + 1)) ++c;
    Column& col = columns[c];
    if (col.count == 0) col.first = s.y(i);
    col.last = s.y(i);
    ++col.count;
    if (s.y(i) < col.min) col.min = s.y(i);
    if (s.y(i) > col.max) col.max = s.y(i);
  }
  return columns;
}

void require_same(const std::vector<Column>& got, const std::vector<Column>& want) {
  REQUIRE(got.size() == want.size());
  for (std::size_t c = 0; c < got.size(); ++c) {
    INFO("column " << c);
    REQUIRE(got[c].count == want[c].count);
    if (want[c].count == 0) continue;
    // Exact: the pyramid holds the samples themselves, not rounded copies.
    REQUIRE(got[c].min == want[c].min);
    REQUIRE(got[c].max == want[c].max);
    REQUIRE(got[c].first == want[c].first);
    REQUIRE(got[c].last == want[c].last);
  }
}

}  // namespace

TEST_CASE("decimation keeps each pixel column's first, last, min and max exactly", "[viewer]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> y(100003);
  for (std::size_t i = 0; i < y.size(); ++i) y[i] = std::sin(i * 1e-3) + 0.1 * noise(rng);
  y[5000] = 40.0;  // single-sample spikes must survive decimation
  y[77777] = -40.0;
  const Series uniform = Series::uniform("force", "N", 0.25, 1e-3, y);
  std::vector<double> t(y.size());
  double now = 0.0;
  std::uniform_real_distribution<double> step(0.2e-3, 1.8e-3);
  for (double& v : t) v = (now += step(rng));
  const Series timed = Series::timed("force", "N", t, y);

  struct Case {
    double x_min, x_max;
    std::size_t width;
  };
  const std::vector<Case> cases = {
      {0.25, 0.25 + 100.002, 1000}, {0.0, 120.0, 997}, {3.1, 3.9, 640}, {5.2, 5.3, 1920},
      {-10.0, 500.0, 333},          {50.0, 50.01, 7}};
  for (const Case& c : cases) {
    INFO("x " << c.x_min << " .. " << c.x_max << ", " << c.width << " px");
    require_same(decimate(uniform, c.x_min, c.x_max, c.width),
                 brute_force(uniform, c.x_min, c.x_max, c.width));
    require_same(decimate(timed, c.x_min, c.x_max, c.width),
                 brute_force(timed, c.x_min, c.x_max, c.width));
  }
  // The spike at sample 5000 is the max of its column at any zoom.
  const auto wide = decimate(uniform, 0.25, 100.25, 200);
  double largest = -1.0;
  for (const Column& col : wide) largest = std::max(largest, col.max);
  REQUIRE(largest == 40.0);
}

TEST_CASE("the min/max pyramid answers every range like a scan, NaN skipped", "[viewer]") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> value(-5.0, 5.0);
  std::vector<double> y(1000);
  for (double& v : y) v = value(rng);
  y[300] = std::numeric_limits<double>::quiet_NaN();
  const MinMaxPyramid pyramid(y);
  std::uniform_int_distribution<std::size_t> index(0, y.size());
  for (int k = 0; k < 2000; ++k) {
    std::size_t a = index(rng), b = index(rng);
    if (a > b) std::swap(a, b);
    if (a == b) continue;
    double want_min = std::numeric_limits<double>::infinity(), want_max = -want_min;
    for (std::size_t i = a; i < b; ++i) {
      if (std::isnan(y[i])) continue;
      want_min = std::min(want_min, y[i]);
      want_max = std::max(want_max, y[i]);
    }
    double got_min, got_max;
    pyramid.range(y, a, b, got_min, got_max);
    INFO("range " << a << " .. " << b);
    REQUIRE(got_min == want_min);
    REQUIRE(got_max == want_max);
  }
}

TEST_CASE("decimate refuses x-y series and empty ranges, naming them", "[viewer]") {
  const Series loop = Series::xy("loop", "rad", "N", {0, 1}, {2, 3});
  REQUIRE_THROWS_WITH(decimate(loop, 0, 1, 10), Catch::Contains("'loop' is an x-y series"));
  const Series s = Series::uniform("a", "N", 0, 1, {1, 2, 3});
  REQUIRE_THROWS_WITH(decimate(s, 1, 1, 10), Catch::Contains("x_max > x_min"));
  REQUIRE_THROWS_WITH(decimate(s, 0, 1, 0), Catch::Contains("width_px"));
  REQUIRE_THROWS_WITH(Series::timed("t", "N", {0, 2, 1}, {0, 0, 0}),
                      Catch::Contains("'t': times decrease at sample 2"));
}

TEST_CASE("wheel zoom keeps the data point under the cursor where it was", "[viewer]") {
  PlotView view;
  view.add(std::make_shared<Series>(Series::uniform("a", "N", 0, 0.01, std::vector<double>(1000))));
  *view.x = {0.0, 10.0};
  view.y = {-2.0, 2.0};
  const Rect r{40, 20, 800, 400};
  const double px = 250.0, py = 100.0;
  const double x_before = view.from_px_x(px, r), y_before = view.from_px_y(py, r);
  view.zoom_about(0.5, px, py, r, true);
  REQUIRE(view.x->span() == Approx(5.0));
  REQUIRE(view.y.span() == Approx(2.0));
  REQUIRE(view.to_px_x(x_before, r) == Approx(px));
  REQUIRE(view.to_px_y(y_before, r) == Approx(py));
  view.zoom_about(3.0, 700.0, 300.0, r, false);  // x only: y untouched
  REQUIRE(view.y.span() == Approx(2.0));
  REQUIRE(view.x->span() == Approx(15.0));
}

TEST_CASE("pan follows the mouse and box zoom shows exactly the box", "[viewer]") {
  PlotView view;
  *view.x = {0.0, 10.0};
  view.y = {0.0, 4.0};
  const Rect r{0, 0, 1000, 400};
  const double x_at = view.from_px_x(300, r), y_at = view.from_px_y(100, r);
  view.pan_px(50, -20, r);  // the point that was at (300,100) is now at (350,80)
  REQUIRE(view.to_px_x(x_at, r) == Approx(350));
  REQUIRE(view.to_px_y(y_at, r) == Approx(80));
  *view.x = {0.0, 10.0};
  view.y = {0.0, 4.0};
  REQUIRE(view.box_zoom(600, 300, 200, 100, r));  // corners in any order
  REQUIRE(view.x->min == Approx(2.0));
  REQUIRE(view.x->max == Approx(6.0));
  REQUIRE(view.y.min == Approx(1.0));
  REQUIRE(view.y.max == Approx(3.0));
  REQUIRE_FALSE(view.box_zoom(10, 10, 11, 200, r));  // a click is not a box
}

TEST_CASE("linked time axes follow each other, y stays each plot's own", "[viewer]") {
  PlotView force, angle, loop;
  force.title = "force";
  angle.title = "angle";
  angle.link_x_to(force);
  *force.x = {0.0, 10.0};
  force.y = {-1.0, 1.0};
  angle.y = {0.0, 2.0};
  const Rect r{0, 0, 500, 200};
  angle.zoom_about(0.1, 250, 100, r, true);
  REQUIRE(force.x->min == Approx(4.5));
  REQUIRE(force.x->max == Approx(5.5));
  REQUIRE(force.y.min == -1.0);  // untouched
  force.pan_px(100, 0, r);
  REQUIRE(angle.x->min == Approx(4.3));
  *loop.x = {7.0, 8.0};  // not linked: unaffected
  force.box_zoom(0, 0, 250, 200, r);
  REQUIRE(loop.x->min == 7.0);
  REQUIRE(angle.x->max == Approx(force.x->max));
}

TEST_CASE("the crosshair reads the nearest sample of each series", "[viewer]") {
  PlotView view;
  auto s = std::make_shared<Series>(Series::uniform("force", "N", 1.0, 0.5, {10, 11, 12, 13}));
  view.add(s);
  view.fit(0.0);
  const Rect r{0, 0, 150, 100};
  // x = 1.0 .. 2.5 over 150 px: pixel 80 is x = 1.8, nearest sample x = 2.0 (index 2).
  auto readout = view.readout(80, 50, r);
  REQUIRE(readout.size() == 1);
  REQUIRE(readout[0].index == 2);
  REQUIRE(readout[0].x == 2.0);
  REQUIRE(readout[0].y == 12.0);
  REQUIRE(readout[0].unit == "N");

  PlotView loop;
  loop.add(std::make_shared<Series>(Series::xy("loop", "rad", "N", {0, 1, 1, 0}, {0, 0, 1, 1})));
  *loop.x = {0, 1};
  loop.y = {0, 1};
  readout = loop.readout(95, 10, Rect{0, 0, 100, 100});  // near (1, 1)
  REQUIRE(readout.at(0).index == 2);
}

TEST_CASE("draw data: a column's vertical extent spans its min and max", "[viewer]") {
  std::vector<double> y(100000, 0.0);
  y[50000] = 1.0;
  PlotView view;
  auto s = std::make_shared<Series>(Series::uniform("a", "N", 0, 1, y));
  s->colour = {255, 0, 0, 255};
  view.add(s);
  *view.x = {0.0, 99999.0};
  view.y = {0.0, 1.0};
  const Rect r{10, 0, 100, 100};
  DrawData data;
  view.build_draw_data(r, data);
  REQUIRE(data.visible_samples == 100000);
  REQUIRE(data.strips.size() == 1);
  REQUIRE(data.strips[0].colour == Rgba{255, 0, 0, 255});
  // 4 points a column, 100 columns; the spike's column reaches y pixel 0 (value 1).
  REQUIRE(data.points.size() == 400);
  float top = 1e9f;
  for (const Point& p : data.points) top = std::min(top, p.y);
  REQUIRE(top == 0.0f);
  // NaN breaks a line into two strips.
  auto gap = std::make_shared<Series>(
      Series::uniform("b", "N", 0, 1, {0, 1, std::numeric_limits<double>::quiet_NaN(), 1, 0}));
  PlotView small;
  small.add(gap);
  small.fit();
  small.build_draw_data(r, data);
  REQUIRE(data.strips.size() == 2);
}

TEST_CASE("axis ticks are round steps inside the range", "[viewer]") {
  REQUIRE(nice_ticks(0.0, 10.0, 5) == std::vector<double>{0, 2, 4, 6, 8, 10});
  const auto ticks = nice_ticks(-0.013, 0.041, 6);
  REQUIRE(ticks.front() == Approx(-0.01));
  REQUIRE(ticks.back() == Approx(0.04));
  REQUIRE(tick_label(0.01, 0.01) == "0.01");
  REQUIRE(tick_label(250, 50) == "250");
  REQUIRE(nice_ticks(1.0, 1.0).empty());
}

TEST_CASE("a plot's visible data exports to CSV, only what is in view", "[viewer]") {
  PlotView view;
  view.add(std::make_shared<Series>(Series::uniform("force", "N", 0.0, 0.5, {1, 2, 3, 4, 5})));
  *view.x = {0.4, 1.5};
  view.y = {0, 10};
  REQUIRE(visible_csv(view) ==
          "series,x,y,x_unit,y_unit\n"
          "force,0.5,2,s,N\n"
          "force,1,3,s,N\n"
          "force,1.5,4,s,N\n");
  PlotView loop;
  loop.add(
      std::make_shared<Series>(Series::xy("opening", "rad", "N", {0.1, 0.2, 0.9}, {1, 50, 2})));
  *loop.x = {0, 1};
  loop.y = {0, 10};  // (0.2, 50) is above the box
  REQUIRE(visible_csv(loop) ==
          "series,x,y,x_unit,y_unit\n"
          "opening,0.10000000000000001,1,rad,N\n"
          "opening,0.90000000000000002,2,rad,N\n");
}

TEST_CASE("the residual loop's steps are read from the loop's result.json", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_steps");
  {
    std::ofstream out(dir.path / "result.json");
    out << R"({"source": "s.h5", "steps": [
      {"step": 1, "effect": "gravity_imbalance", "evidence": {"explained_fraction": 0.8},
       "parameters": [{"name": "imbalance_Nm", "unit": "N m", "value": 1.5,
                       "standard_uncertainty": 0.02}],
       "before": {"fitted_rmse_rad_s": 0.30, "held_out_rmse_rad_s": 0.35, "bic": 10},
       "after": {"fitted_rmse_rad_s": 0.05, "held_out_rmse_rad_s": 0.06, "bic": 2},
       "held_out_improvement": 0.83, "bic_change": -8},
      {"step": 2, "effect": "stribeck", "parameters": [],
       "before": {"fitted_rmse_rad_s": 0.05, "held_out_rmse_rad_s": 0.06},
       "after": {"fitted_rmse_rad_s": 0.04, "held_out_rmse_rad_s": null},
       "held_out_improvement": 0.1, "bic_change": -1}]})";
  }
  const LoopSteps steps = read_loop_steps(dir.path);  // the folder, as `loop --out` made it
  REQUIRE(steps.source == "s.h5");
  REQUIRE(steps.steps.size() == 2);
  REQUIRE(steps.steps[0].effect == "gravity_imbalance");
  REQUIRE(steps.steps[0].parameters == "imbalance_Nm = 1.5 ± 0.02 N m");
  REQUIRE(steps.steps[0].held_out_before_rad_s == 0.35);
  REQUIRE(steps.steps[0].held_out_after_rad_s == 0.06);
  REQUIRE(std::isnan(steps.steps[1].held_out_after_rad_s));
  const PlotView plot = loop_steps_plot(steps);
  REQUIRE(plot.series.size() == 2);
  REQUIRE(plot.series[0]->size() == 3);  // start model, step 1, step 2
  REQUIRE(plot.series[0]->y(0) == 0.30);
  REQUIRE(plot.series[0]->y(2) == 0.04);
  REQUIRE(plot.y.min == 0.0);

  {
    std::ofstream out(dir.path / "bad.json");
    out << R"({"steps": [{"step": 1, "effect": "x", "before": {}}]})";
  }
  REQUIRE_THROWS_WITH(read_loop_steps(dir.path / "bad.json"),
                      Contains("bad.json: steps[0]: no field 'after'"));
}
