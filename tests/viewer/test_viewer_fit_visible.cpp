// Measured stays visible under a perfect fit: in the viewer's fit layout a
// model's curve equal to the measured one must not hide it. The screenshot is taken in a
// child run of this test binary under Xvfb (a hidden test case, so that the fit comparison
// can be made exactly equal to the measurement), then its pixels are read here.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>

#include "acquisition/session/session_file.h"
#include "fixtures/temp_dir.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"
#include "viewer/viewer_app.h"
#include "viewer/window.h"

namespace fs = std::filesystem;
using namespace doorbench;

namespace {

constexpr double kRateAmplitude = 1.5;  // rad/s

double known_rate(double t) {
  return kRateAmplitude * std::sin(2.0 * std::numbers::pi * 0.4 * t);
}

}  // namespace

// Run by the test below under Xvfb: the fit layout of a comparison whose simulated curve is
// the measured one, sample for sample, written to $DOORBENCH_TEST_PNG. Hidden and tagged
// [child]: a step of the test below in a process of its own, never a check on its own
// (check_test_names allows exactly such hidden tests).
TEST_CASE("fit layout screenshot with simulated = measured (child of the test below)",
          "[.][child]") {
  const char* png = std::getenv("DOORBENCH_TEST_PNG");
  REQUIRE(png != nullptr);
  const fs::path session_path = fs::path(png).parent_path() / "small.h5";
  testing::write_force_session(session_path, std::vector<double>(100, 0.0), 100.0);
  std::vector<double> t, omega;
  for (int i = 0; i <= 5000; ++i) {
    t.push_back(i * 0.002);
    omega.push_back(known_rate(t.back()));
  }
  viewer::FitComparison fit;
  fit.model_description = "perfect model";
  fit.measured =
      std::make_shared<viewer::Series>(viewer::Series::timed("measured", "rad/s", t, omega));
  fit.simulated =
      std::make_shared<viewer::Series>(viewer::Series::timed("simulated", "rad/s", t, omega));
  fit.residual = std::make_shared<viewer::Series>(
      viewer::Series::timed("residual", "rad/s", t, std::vector<double>(t.size(), 0.0)));
  viewer::style_series(*fit.measured, plot_style::Meaning::kMeasured);
  viewer::style_series(*fit.simulated, plot_style::Meaning::kSimulated);
  viewer::style_series(*fit.residual, plot_style::Meaning::kResidual);
  std::vector<viewer::SessionData> sessions;
  sessions.push_back(viewer::load_session(session_path, {false}));
  std::vector<std::optional<viewer::FitComparison>> fits;
  fits.emplace_back(std::move(fit));
  viewer::Viewer view(std::move(sessions), std::move(fits));
  viewer::WindowOptions window;
  window.width_px = 1000;
  window.height_px = 700;
  viewer::screenshot(view, "fit", png, window);
}

TEST_CASE("in the fit layout the measured curve stays visible when the model matches it exactly",
          "[viewer][xvfb]") {
  testing::TempDir dir("viewer_fit_visible");
  const fs::path png = dir.path / "fit.png";
  const fs::path self = fs::read_symlink("/proc/self/exe");
  std::string err;
  const int status = testing::run_under_xvfb(
      "env DOORBENCH_TEST_PNG='" + png.string() + "' '" + self.string() + "' '[.][child]'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const testing::Screenshot shot = testing::load_screenshot(png);
  const auto& plot = shot.plot("rate:");
  REQUIRE(plot["series"][0]["name"] == "measured");
  REQUIRE(plot["series"][1]["name"] == "simulated");
  const std::vector<int> measured = plot["series"][0]["rgb"];
  const testing::PlotGeometry g(plot);
  // Along the whole curve, 40 columns from end to end: the measured colour itself (not a
  // blend with the model's) is on the curve in every one.
  int seen = 0;
  for (int k = 1; k <= 40; ++k) {
    const int x = int(g.x0 + g.w * k / 41.0);
    const auto [lo, hi] = testing::curve_rows(g, known_rate, x, 1.0);
    bool found = false;
    for (int y = std::max(g.top(), int(lo) - 3); y <= std::min(g.bottom(), int(hi) + 3); ++y) {
      found = found || testing::near_rgb(shot.pixel(x, y), measured, 30);
    }
    INFO("column " << x << ", curve rows " << lo << ".." << hi);
    CHECK(found);
    seen += found;
  }
  REQUIRE(seen == 40);
}
