// `doorbench view --screenshot` for real: the doorbench executable under Xvfb (xvfb-run,
// Mesa's software OpenGL) draws a session with a known sine, and the PNG's pixels must show
// the series colour along the curve, and nowhere else in the plot's data area. Also the
// session-loading model behind the views, on the same session. PNGs are read with stb_image
// (libstb).
#include <stb_image.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/model/parameter_file.h"
#include "fixtures/temp_dir.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;

namespace {

constexpr double kAmplitudeN = 2.0;
constexpr double kFrequencyHz = 0.5;
constexpr double kRateHz = 1000.0;
constexpr double kDurationS = 4.0;
constexpr double kFirstSampleS = 0.5;

double known_force(double t) {
  return kAmplitudeN * std::sin(2.0 * std::numbers::pi * kFrequencyHz * (t - kFirstSampleS));
}

// A session with one channel, "force", holding the known sine (values in N, no calibration),
// delayed by delay_s, with an opening stroke_start event at stroke_s when it is >= 0.
void write_sine_session(const fs::path& path, double delay_s = 0.0, double stroke_s = -1.0) {
  doorbench::SessionMetadata metadata;
  metadata.rig_name = "viewer-test";
  metadata.operator_name = "test";
  doorbench::SessionWriter writer(path, metadata);
  doorbench::ChannelInfo channel;
  channel.name = "force";
  channel.sensor_kind = "imported";
  channel.raw_type = doorbench::RawType::kValues;
  channel.raw_unit = "N";
  channel.unit = "N";
  channel.range_min = -100;
  channel.range_max = 100;
  channel.sample_rate_hz = kRateHz;
  channel.first_sample_time_s = kFirstSampleS;
  const int index = writer.add_channel(channel);
  std::vector<double> values(std::size_t(kDurationS * kRateHz));
  for (std::size_t i = 0; i < values.size(); ++i) {
    values[i] = known_force(kFirstSampleS + double(i) / kRateHz - delay_s);
  }
  writer.append_values(index, values);
  writer.add_event({1.0, "mark", "", "a mark"});
  if (stroke_s >= 0.0) {
    writer.add_event({stroke_s + 0.7, "stroke_start", "", "closing"});  // not the first
    writer.add_event({stroke_s, "stroke_start", "", "opening"});
  }
  writer.close();
}

struct Run {
  int exit_code = -1;
  std::string err;
};

Run run(const std::string& arguments, const fs::path& dir) {
  const fs::path err = dir / "stderr.txt";
  const std::string command = std::string(DOORBENCH_EXECUTABLE)
                                  .append(" ")
                                  .append(arguments)
                                  .append(" >/dev/null 2>")
                                  .append(err.string());
  const int status = std::system(command.c_str());
  Run result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::ostringstream text;
  text << in.rdbuf();
  result.err = text.str();
  return result;
}

}  // namespace

TEST_CASE("view --screenshot draws the known sine where it belongs, and only there",
          "[viewer][xvfb]") {
  doorbench::testing::TempDir dir("viewer_screenshot");
  const fs::path session = dir.path / "sine.h5";
  const fs::path png = dir.path / "channels.png";
  write_sine_session(session);
  // xvfb-run (package xvfb) starts a private X server; Mesa draws in software.
  std::string err;
  const int status = doorbench::testing::run_under_xvfb(
      "'" DOORBENCH_EXECUTABLE "' view --screenshot '" + png.string() +
          "' --layout channels --width 900 --height 600 '" + session.string() + "'",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);

  const doorbench::testing::Screenshot shot = doorbench::testing::load_screenshot(png);
  REQUIRE(shot.width == 900);
  REQUIRE(shot.height == 600);
  const nlohmann::json& info = shot.info;
  REQUIRE(info["plots"].size() == 1);
  const auto& plot = info["plots"][0];
  REQUIRE(plot["title"] == "force");
  REQUIRE(plot["series"][0]["name"] == "force");
  const std::vector<int> rgb = plot["series"][0]["rgb"];
  const std::vector<double> area = plot["area_px"];
  const std::vector<double> xr = plot["x_range"], yr = plot["y_range"];
  // The plot fills the window (less margins) and shows the whole recording.
  REQUIRE(area[2] > 700);
  REQUIRE(area[3] > 450);
  REQUIRE(xr[0] == Approx(kFirstSampleS));
  REQUIRE(xr[1] == Approx(kFirstSampleS + kDurationS - 1.0 / kRateHz));
  REQUIRE(yr[0] < -kAmplitudeN);
  REQUIRE(yr[1] > kAmplitudeN);

  doorbench::testing::require_curve_drawn_where_it_belongs(
      shot.rgb.data(), shot.width, doorbench::testing::PlotGeometry(plot), rgb, known_force);
}

TEST_CASE("view refuses a screenshot without a layout or with an unknown one", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_cli");
  const fs::path session = dir.path / "sine.h5";
  write_sine_session(session);
  const fs::path png = dir.path / "x.png";
  Run r = run("view --screenshot " + png.string() + " " + session.string(), dir.path);
  REQUIRE(r.exit_code == 2);
  REQUIRE(r.err ==
          "doorbench: --screenshot needs --layout, the view to render: one of browser, channels, "
          "loop, fit, overlay, steps, tuning (see doorbench view --help)\n");
  r = run("view --screenshot " + png.string() + " --layout nope " + session.string(), dir.path);
  REQUIRE(r.exit_code == 2);
  REQUIRE_THAT(r.err, Contains("unknown layout 'nope' (expected browser, channels, loop, fit, "
                               "overlay, steps, tuning or live)"));
  REQUIRE_FALSE(fs::exists(png));
}

TEST_CASE("the viewer's session model: channels in physical units, events, linked plots",
          "[viewer]") {
  doorbench::testing::TempDir dir("viewer_model");
  const fs::path path = dir.path / "sine.h5";
  write_sine_session(path);
  const auto session = doorbench::viewer::load_session(path);
  REQUIRE(session.metadata.rig_name == "viewer-test");
  REQUIRE(session.channels.size() == 1);
  REQUIRE(session.sample_counts[0] == 4000);
  REQUIRE(session.events.size() == 1);
  const auto& s = *session.channel_series[0];
  REQUIRE(s.unit() == "N");
  REQUIRE(s.x(0) == kFirstSampleS);
  REQUIRE(s.y(500) == Approx(known_force(kFirstSampleS + 0.5)));
  // A sine is no door: no strokes, and the model says why instead of failing.
  REQUIRE_FALSE(session.prepared);
  REQUIRE_FALSE(session.prepare_message.empty());
  REQUIRE_THROWS_WITH(
      doorbench::viewer::compare_with_model(
          session, doorbench::reference_model(doorbench::ModelKind::kSensory), "reference"),
      Contains("no strokes to compare the model with"));
  auto plots = doorbench::viewer::channel_plots(session);
  REQUIRE(plots.size() == 1);
  REQUIRE(plots[0].y.min < -kAmplitudeN);
  REQUIRE(plots[0].y.max > kAmplitudeN);
}

TEST_CASE("the A/B overlay aligns two sessions on their first stroke start", "[viewer]") {
  doorbench::testing::TempDir dir("viewer_overlay");
  // B is A delayed by 1.25 s, and its stroke starts 1.25 s later: aligned, they coincide.
  write_sine_session(dir.path / "a.h5", 0.0, 1.5);
  write_sine_session(dir.path / "b.h5", 1.25, 2.75);
  const auto a = doorbench::viewer::load_session(dir.path / "a.h5", {false});
  const auto b = doorbench::viewer::load_session(dir.path / "b.h5", {false});
  REQUIRE(doorbench::viewer::first_stroke_start_s(a) == 1.5);
  REQUIRE(doorbench::viewer::first_stroke_start_s(b, "closing") == Approx(3.45));
  const auto overlay = doorbench::viewer::overlay_plots(a, b);
  REQUIRE(overlay.a_start_s == 1.5);
  REQUIRE(overlay.b_start_s == 2.75);
  REQUIRE(overlay.plots.size() == 1);
  // Not prepared into strokes: the raw channels, and the header says why.
  CHECK(overlay.shown == "raw channels: a.h5 is not prepared into strokes (strokes not prepared)");
  const auto& plot = overlay.plots[0];
  CHECK(plot.title.rfind("channel ", 0) == 0);
  REQUIRE(plot.series.size() == 2);
  REQUIRE(plot.series[0]->name() == "A a.h5");
  REQUIRE(plot.series[1]->name() == "B b.h5");
  // Where both have samples, A and B read the same at the same time since stroke start.
  for (double x : {-0.5, 0.0, 0.3, 1.1, 1.6}) {
    INFO("x " << x);
    const auto& sa = *plot.series[0];
    const auto& sb = *plot.series[1];
    const std::size_t ia = sa.nearest(x), ib = sb.nearest(x);
    REQUIRE(sa.x(ia) == Approx(x).margin(1e-9));
    REQUIRE(sb.x(ib) == Approx(x).margin(1e-9));
    REQUIRE(sa.y(ia) == Approx(sb.y(ib)).margin(1e-9));
  }
  // Without stroke events there is nothing to align on: the message names the session.
  write_sine_session(dir.path / "c.h5");
  const auto c = doorbench::viewer::load_session(dir.path / "c.h5", {false});
  REQUIRE_THROWS_WITH(doorbench::viewer::overlay_plots(a, c),
                      Contains("c.h5: no stroke_start event to align on"));
  // Events become markers on the time axis: the mark and both stroke starts.
  const auto markers = doorbench::viewer::event_markers(a, "force");
  REQUIRE(markers.size() == 3);
  REQUIRE(markers[0].x == 1.0);
  REQUIRE(markers[0].label == "mark a mark");
  REQUIRE(markers[2].label == "stroke_start opening");
}
