// The viewer's units and sensor limits: angles and rates are shown
// in degrees as the reports show them (the session keeps rad; plot_style::display_unit says
// which units), and the channels layout shades the stretches where a channel sits at its
// sensor's limit (sensors/channel_limits.h, the definition `doorbench record` warns with). A
// session of the simulated bench's rig with one inclinometer channel, "angle", that is held at
// the sensor's 10 deg end from 0.995 s to 1.505 s.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <vector>

#include "acquisition/rig/rig_file.h"
#include "acquisition/session/session_file.h"
#include "core/units.h"
#include "fixtures/temp_dir.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"

namespace fs = std::filesystem;
using namespace doorbench;

namespace {

constexpr double kRateHz = 1000.0;
constexpr double kEndRad = 10.0 * kRadPerDeg;  // the inclinometer's range

// 0 until 0.5 s, up to the range's end at 1.0 s, held there until 1.5 s, back to 0 at 2.0 s,
// 0 until 3 s. At the limit (99 % of the range): from 0.995 s to 1.505 s.
double known_angle_rad(double t) {
  if (t < 0.5 || t >= 2.0) return 0.0;
  if (t < 1.0) return kEndRad * (t - 0.5) / 0.5;
  if (t < 1.5) return kEndRad;
  return kEndRad * (2.0 - t) / 0.5;
}

void write_angle_session(const fs::path& path, bool with_rig) {
  SessionMetadata metadata;
  metadata.rig_name = "simulated-dishwasher";
  if (with_rig) metadata.rig_definition = std::string(simulated_dishwasher_rig_text());
  std::vector<double> values;
  for (int i = 0; i < 3000; ++i) values.push_back(known_angle_rad(i / kRateHz));
  testing::write_channel_session(path, "angle", "inclinometer", "rad", 1.0, values, kRateHz,
                                 metadata);
}

}  // namespace

TEST_CASE("viewer: angles in deg, the session's rad converted at display", "[viewer]") {
  testing::TempDir dir("viewer_units");
  const fs::path path = dir.path / "angle.h5";
  write_angle_session(path, true);
  const viewer::SessionData session = viewer::load_session(path, {false});
  REQUIRE(session.channel_series.size() == 1);
  const viewer::Series& angle = *session.channel_series[0];
  CHECK(angle.unit() == "deg");
  CHECK(angle.y(750) == Approx(5.0));
  CHECK(angle.y(1200) == Approx(10.0));
  CHECK(session.channels[0].unit == "rad");  // the session's record is as stored

  std::vector<double> rates = {1.0, -0.5, std::nan("")};
  CHECK(viewer::to_display_units("rad/s", rates) == "deg/s");
  CHECK(rates[0] == Approx(doorbench::kDegPerRad));
  CHECK(rates[1] == Approx(-90.0 / std::numbers::pi));
  CHECK(std::isnan(rates[2]));
  std::vector<double> forces = {2.0};
  CHECK(viewer::to_display_units("N", forces) == "N");
  CHECK(forces[0] == 2.0);
}

TEST_CASE("viewer: a channel's stretches at its sensor's limit, from the session's rig",
          "[viewer]") {
  testing::TempDir dir("viewer_limits");
  const fs::path path = dir.path / "angle.h5";
  write_angle_session(path, true);
  const viewer::SessionData session = viewer::load_session(path, {false});
  REQUIRE(session.at_limit.size() == 1);
  REQUIRE(session.at_limit[0].size() == 1);
  const viewer::Shade& shade = session.at_limit[0][0];
  CHECK(shade.x0 == Approx(0.995).margin(0.0025));
  CHECK(shade.x1 == Approx(1.505).margin(0.0025));
  CHECK(shade.label == "inclinometer angle at its ±10 deg limit");
  const std::vector<viewer::PlotView> plots = viewer::channel_plots(session);
  REQUIRE(plots.size() == 1);
  CHECK(plots[0].shades.size() == 1);

  // Without the rig the limit is not known: nothing is shaded.
  const fs::path bare = dir.path / "bare.h5";
  write_angle_session(bare, false);
  const viewer::SessionData unknown = viewer::load_session(bare, {false});
  REQUIRE(unknown.at_limit.size() == 1);
  CHECK(unknown.at_limit[0].empty());
}

TEST_CASE("view --screenshot: the channels layout in deg, the stretch at the limit shaded",
          "[viewer][xvfb]") {
  testing::TempDir dir("viewer_units_limits_png");
  const fs::path session = dir.path / "angle.h5";
  const fs::path png = dir.path / "channels.png";
  write_angle_session(session, true);
  std::string err;
  const int status = testing::run_under_xvfb(
      std::string("'" DOORBENCH_EXECUTABLE "' view ") + "--screenshot '" + png.string() +
          "' --layout channels --width 900 --height 600 '" + session.string() + "'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const testing::Screenshot shot = testing::load_screenshot(png);
  const auto& plot = shot.plot("angle");
  // The header says deg, and the shade's meaning.
  const std::vector<std::string> labels = plot["labels"];
  CHECK(std::find(labels.begin(), labels.end(), "angle [deg]") != labels.end());
  CHECK(std::find(labels.begin(), labels.end(),
                  "shaded: inclinometer angle at its ±10 deg limit") != labels.end());
  // The values in deg: 0 … 10 with the 5 % margin.
  const testing::PlotGeometry g(plot);
  CHECK(g.ymax == Approx(10.5).margin(0.01));
  CHECK(g.ymin == Approx(-0.5).margin(0.01));

  // Below the curve (at 2.5 … 3.5 deg, where the held angle is at 10 deg), the stretch's
  // columns are red against the same rows outside it (the curve at 0 or above 6 deg there).
  auto redness = [&](double t, double deg) {
    const unsigned char* p = shot.pixel(int(std::lround(g.column_of(t))), int(g.row_of(deg)));
    return int(p[0]) - int(p[1]);
  };
  for (double deg : {2.5, 3.0, 3.5}) {
    for (double t_in : {1.05, 1.2, 1.33, 1.45}) {
      for (double t_out : {0.2, 0.92, 1.58, 2.4, 2.8}) {
        INFO("at " << deg << " deg: t " << t_in << " s (shaded) against t " << t_out << " s");
        CHECK(redness(t_in, deg) > redness(t_out, deg) + 30);
      }
    }
  }
}
