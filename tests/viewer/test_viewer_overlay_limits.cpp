// The overlay marks what it cannot know: a simulated-bench session of the physical door, which
// falls open faster than the gyroscope's ±100 deg/s, overlaid with one of the sensory door.
// Where A's gyroscope sat at its limit the overlay's door plots are shaded (with the
// session's name and what is not known) and the fused angle and rate leave those samples
// out; where the angle is shown, it is the truth's to a fraction of a degree, also after a
// clipped stretch (preprocessing restarts it from the inclinometer's anchors, never from
// the integral of a clipped rate). The real `doorbench view --layout overlay --screenshot`
// under Xvfb draws the shade.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "core/units.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"

namespace fs = std::filesystem;
using namespace doorbench;

namespace {

// The sessions: A the physical door (its gyroscope saturates in every opening), B the
// sensory door, 12 s each.
struct OverlayPair {
  testing::TempDir dir{"viewer_overlay_limits"};
  fs::path a = dir.path / "fast.h5", b = dir.path / "slow.h5";
  OverlayPair() {
    testing::record_built_in_session(a, 12.0, 3, "physical");
    testing::record_built_in_session(b, 12.0, 4, "sensory");
  }
};

// The index of the session's gyroscope channel.
std::size_t gyroscope_index(const viewer::SessionData& session) {
  for (std::size_t i = 0; i < session.channels.size(); ++i) {
    if (session.channels[i].sensor_kind == "gyroscope") return i;
  }
  FAIL("no gyroscope channel");
  return 0;
}

}  // namespace

TEST_CASE(
    "overlay: where a gyroscope sat at its limit the door's quantities are shaded and "
    "left out, and the angle after it is the truth's",
    "[viewer]") {
  const OverlayPair pair;
  const viewer::SessionData a = viewer::load_session(pair.a);
  const viewer::SessionData b = viewer::load_session(pair.b);
  REQUIRE(a.prepared);
  REQUIRE(b.prepared);
  const std::vector<viewer::Shade>& clipped = a.at_limit[gyroscope_index(a)];
  REQUIRE(clipped.size() >= 2);  // each opening of the physical door
  CHECK(b.at_limit[gyroscope_index(b)].empty());

  const viewer::Overlay overlay = viewer::overlay_plots(a, b);
  REQUIRE(overlay.plots.size() == 3);
  for (const viewer::PlotView& plot : overlay.plots) {
    INFO(plot.title);
    REQUIRE(plot.shades.size() == clipped.size());
    for (std::size_t k = 0; k < clipped.size(); ++k) {
      CHECK(plot.shades[k].x0 == clipped[k].x0 - overlay.a_start_s);
      CHECK(plot.shades[k].x1 == clipped[k].x1 - overlay.a_start_s);
      CHECK(plot.shades[k].label ==
            "A fast.h5: gyroscope rate at its ±100 deg/s limit, the door's angle and rate not "
            "known there");
    }
  }

  // Left out: no finite angle or rate inside a clipped stretch.
  for (const viewer::Series* series : {a.door_angle.get(), a.door_rate.get()}) {
    for (std::size_t i = 0; i < series->size(); ++i) {
      if (!std::isfinite(series->y(i))) continue;
      for (const viewer::Shade& shade : clipped) {
        INFO(series->name() << " at " << series->x(i) << " s");
        CHECK_FALSE((series->x(i) > shade.x0 && series->x(i) < shade.x1));
      }
    }
  }

  // Where shown, the fused angle is the truth's, before and after each clipped stretch.
  const SessionReader session(pair.a);
  const std::vector<double> truth_t = session.read_group_dataset("truth", "time_s");
  const std::vector<double> truth_theta = session.read_group_dataset("truth", "theta_rad");
  double worst_deg = 0.0;
  std::size_t after_clipping = 0;
  for (std::size_t i = 0; i < a.door_angle->size(); ++i) {
    const double t = a.door_angle->x(i), deg = a.door_angle->y(i);
    if (!std::isfinite(deg)) continue;
    const auto at = std::lower_bound(truth_t.begin(), truth_t.end(), t - 1e-9);
    REQUIRE(at != truth_t.end());
    const double truth_deg = truth_theta[std::size_t(at - truth_t.begin())] * kDegPerRad;
    worst_deg = std::max(worst_deg, std::abs(deg - truth_deg));
    after_clipping += t > clipped.front().x1 ? 1 : 0;
  }
  CHECK(after_clipping > 1000);
  INFO("worst fused angle error " << worst_deg << " deg");
  CHECK(worst_deg < 0.1);  // measured: 0.015 deg
}

TEST_CASE("view --screenshot: the overlay shades where A's gyroscope sat at its limit",
          "[viewer][xvfb]") {
  const OverlayPair pair;
  const fs::path png = pair.dir.path / "overlay.png";
  std::string err;
  const int status =
      testing::run_under_xvfb(std::string("'" DOORBENCH_EXECUTABLE "' view ") + "--screenshot '" +
                                  png.string() + "' --layout overlay --width 1200 --height 900 '" +
                                  pair.a.string() + "' '" + pair.b.string() + "'",
                              pair.dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const testing::Screenshot shot = testing::load_screenshot(png);
  const auto& plot = shot.plot("angle (fused)");
  const std::vector<std::string> labels = plot["labels"];
  CHECK(std::find(labels.begin(), labels.end(),
                  "shaded: A fast.h5: gyroscope rate at its ±100 deg/s limit, the door's angle "
                  "and rate not known there") != labels.end());

  // The shade's columns are red through the plot's height; the columns between are not.
  const viewer::SessionData a = viewer::load_session(pair.a);
  const viewer::SessionData b = viewer::load_session(pair.b);
  const viewer::Overlay overlay = viewer::overlay_plots(a, b);
  const testing::PlotGeometry g(plot);
  const auto red_share = [&](double x) {
    const int column = int(std::lround(g.column_of(x)));
    int red = 0, all = 0;
    for (int y = g.top(); y <= g.bottom(); ++y, ++all) {
      const unsigned char* p = shot.pixel(column, y);
      red += (int(p[0]) - int(p[1]) > 25 && int(p[0]) - int(p[2]) > 25) ? 1 : 0;
    }
    return double(red) / all;
  };
  const std::vector<viewer::Shade>& shades = overlay.plots.front().shades;
  REQUIRE(shades.size() >= 2);
  for (std::size_t k = 0; k < shades.size(); ++k) {
    const viewer::Shade& shade = shades[k];
    if (shade.x1 > g.xmax) continue;
    INFO("shade " << k << " from " << shade.x0 << " to " << shade.x1 << " s");
    CHECK(red_share(0.5 * (shade.x0 + shade.x1)) > 0.8);
    if (k + 1 < shades.size()) {
      // Halfway to the next shade, neither curve nor shade fills the column.
      CHECK(red_share(0.5 * (shade.x1 + shades[k + 1].x0)) < 0.2);
    }
  }
}
