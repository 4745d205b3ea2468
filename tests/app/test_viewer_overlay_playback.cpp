// The A/B overlay of the real door and its haptic playback: a bench
// session (the simulated bench, stroke events recorded) and a playback session (the
// simulated HapticMaster's render loop, no stroke events) are overlaid by the real
// `doorbench view --screenshot` under Xvfb; both rate curves must be in the picture and
// leave rest at the same place, the aligned stroke start.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

#include "analysis/model/parameter_file.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"

namespace fs = std::filesystem;
using namespace doorbench;

namespace {

// The sensory reference door played on the simulated HapticMaster for duration_s, its
// virtual user opening and closing it every 10 s, recorded to `path`.
void record_playback(const fs::path& path, double duration_s) {
  const DoorModel door = reference_model(ModelKind::kSensory);
  haptic::DeviceRequest request;
  request.uri = "sim";
  request.simulated_time = true;
  request.hand.duration_s = 10.0;
  haptic::PlaybackOptions options;
  options.duration_s = duration_s;
  options.loop.safety.max_force = 100.0;
  options.loop.safety.max_force_rate = 20000.0;
  haptic::OpenedDevice opened =
      haptic::open_device(request, options.arc, door.geometry().handle_radius_m);
  SessionMetadata metadata;
  metadata.rig_name = "simulated HapticMaster";
  haptic::Playback playback(*opened.device, door, options, path, metadata,
                            haptic::PlaybackSetup{opened.device->name(), "reference door", ""});
  playback.run_simulated([&](double t) { opened.simulated->advance_to(t); });
}

// The first column (from the left) where a pixel of `rgb` lies more than `away_px` rows
// from `rest_row`; -1 when none.
int first_departure(const testing::Screenshot& shot, const testing::PlotGeometry& g,
                    const std::vector<int>& rgb, double rest_row, double away_px) {
  for (int x = g.left(); x <= g.right(); ++x) {
    for (int y = g.top(); y <= g.bottom(); ++y) {
      if (testing::near_rgb(shot.pixel(x, y), rgb, 40) && std::abs(y - rest_row) > away_px) {
        return x;
      }
    }
  }
  return -1;
}

}  // namespace

TEST_CASE("a playback session gets stroke events on read and overlays a bench session aligned",
          "[viewer][xvfb]") {
  testing::TempDir dir("viewer_overlay_playback");
  const fs::path bench = dir.path / "bench.h5", played = dir.path / "played.h5";
  testing::record_built_in_session(bench, 12.0, 3, "sensory");
  record_playback(played, 12.0);

  // The model: the playback's file has no stroke events; they are found on read from its
  // prepared strokes' motion, while the bench's come from its file.
  const viewer::SessionData a = viewer::load_session(bench);
  const viewer::SessionData b = viewer::load_session(played);
  REQUIRE_FALSE(a.strokes_found_on_read);
  REQUIRE(b.strokes_found_on_read);
  REQUIRE(b.prepared);
  REQUIRE(b.data.strokes.size() >= 2);
  std::size_t starts = 0;
  for (const SessionEvent& e : b.events) {
    if (e.kind != "stroke_start") continue;
    REQUIRE(e.time_s == viewer::motion_onset_s(b.data.strokes[starts]));
    ++starts;
  }
  REQUIRE(starts == b.data.strokes.size());
  const viewer::Overlay overlay = viewer::overlay_plots(a, b);
  REQUIRE(overlay.alignment == "motion onset");
  REQUIRE(overlay.a_start_s == viewer::motion_onset_s(a.data.strokes.front()));
  REQUIRE(overlay.b_start_s == viewer::motion_onset_s(b.data.strokes.front()));

  // The picture: both rate curves, leaving rest at the aligned stroke start.
  const fs::path png = dir.path / "overlay.png";
  std::string err;
  const int status = testing::run_under_xvfb(
      std::string(DOORBENCH_EXECUTABLE) + " view '" + bench.string() + "' '" + played.string() +
          "' --layout overlay --screenshot '" + png.string() + "' --width 1200 --height 900",
      dir.path, err);
  INFO("stderr: " << err);
  REQUIRE(status == 0);
  const testing::Screenshot shot = testing::load_screenshot(png);
  // The door's angle, force and rate from the prepared strokes, not the raw channels.
  CHECK_NOTHROW(shot.plot("angle (fused): A and B"));
  CHECK_NOTHROW(shot.plot("force (handle, + opening): A and B"));
  CHECK_THROWS(shot.plot("channel "));
  const auto& plot = shot.plot("rate (");
  REQUIRE(plot["series"].size() == 2);
  const std::vector<int> rgb_a = plot["series"][0]["rgb"], rgb_b = plot["series"][1]["rgb"];
  const testing::PlotGeometry g(plot);
  // Rest before the stroke is in view: a prepared stroke starts before its motion onset.
  REQUIRE(g.xmin < -0.2);
  const double rest_row = g.row_of(0.0);
  const int column_a = first_departure(shot, g, rgb_a, rest_row, 8.0);
  const int column_b = first_departure(shot, g, rgb_b, rest_row, 8.0);
  INFO("A leaves rest at x " << g.x_of(column_a) << " s, B at " << g.x_of(column_b) << " s");
  REQUIRE(column_a >= 0);
  REQUIRE(column_b >= 0);
  // Both leave rest just after the aligned start (0 s), within 0.3 s of it and of each
  // other: unaligned, their starts were seconds apart on their own clocks.
  CHECK(g.x_of(column_a) > -0.05);
  CHECK(g.x_of(column_a) < 0.3);
  CHECK(g.x_of(column_b) > -0.05);
  CHECK(g.x_of(column_b) < 0.3);
  CHECK(std::abs(g.x_of(column_a) - g.x_of(column_b)) < 0.2);
  REQUIRE(std::abs(overlay.a_start_s - overlay.b_start_s) > 0.3);  // a real shift was needed
}

TEST_CASE("a playback session's channels are grouped: door open, device, model and safety closed",
          "[viewer]") {
  testing::TempDir dir("viewer_playback_groups");
  const fs::path played = dir.path / "played.h5";
  record_playback(played, 3.0);
  std::vector<viewer::SessionData> sessions;
  sessions.push_back(viewer::load_session(played, {false}));
  const viewer::SessionData& s = sessions.front();
  std::map<std::string, std::vector<std::string>> groups;
  for (const ChannelInfo& c : s.channels) groups[viewer::channel_group(c)].push_back(c.name);
  CHECK(groups["door"] == std::vector<std::string>{"force", "angle", "rate"});
  CHECK(groups["device"].size() == 12);  // position, velocity, measured and commanded force
  CHECK(std::find(groups["model"].begin(), groups["model"].end(), "model_torque") !=
        groups["model"].end());
  CHECK(groups["model"].size() > 1);  // and its terms
  CHECK(groups["safety"].size() == 5);
  CHECK(groups[""].empty());
  // The window's channels tab draws the door's three plots; the other groups start closed.
  viewer::Viewer view(std::move(sessions), {});
  view.set_initial_layout("channels");
  const auto titles = testing::window_frame_plots(view);
  CHECK(titles == std::vector<std::string>{"force", "angle", "rate"});
}

namespace {

// The plot of the overlay whose title starts with `prefix`; fails the test when none does.
const viewer::PlotView& overlay_plot(const viewer::Overlay& overlay, const std::string& prefix) {
  for (const viewer::PlotView& plot : overlay.plots) {
    if (plot.title.rfind(prefix, 0) == 0) return plot;
  }
  FAIL("no overlay plot titled " << prefix << "...");
  throw std::logic_error("unreachable");
}

// The finite range of a series' values.
std::pair<double, double> value_range(const viewer::Series& series) {
  double low = INFINITY, high = -INFINITY;
  for (double y : series.ys()) {
    if (!std::isfinite(y)) continue;
    low = std::min(low, y);
    high = std::max(high, y);
  }
  return {low, high};
}

// The force of largest magnitude while the door opens (rate above `moving`) and while it
// closes (rate below −moving), the rate read at each force sample's time (within 5 ms).
struct StrokeForces {
  double opening_N = 0.0, closing_N = 0.0;
};
StrokeForces extreme_forces(const viewer::Series& force, const viewer::Series& rate,
                            double moving) {
  StrokeForces out;
  for (std::size_t i = 0; i < force.size(); ++i) {
    const double f = force.y(i);
    const std::size_t j = rate.lower_index(force.x(i));
    if (!std::isfinite(f) || j >= rate.size() || std::abs(rate.x(j) - force.x(i)) > 0.005) {
      continue;
    }
    const double r = rate.y(j);
    if (r > moving && std::abs(f) > std::abs(out.opening_N)) out.opening_N = f;
    if (r < -moving && std::abs(f) > std::abs(out.closing_N)) out.closing_N = f;
  }
  return out;
}

}  // namespace

TEST_CASE(
    "the overlay of the demo's bench recording and its playback shows the door's angle "
    "over the same range and its forces with the same sign",
    "[viewer]") {
  // The demo's two recordings, shorter: the bench records the sensory reference door with
  // the undeclared gravity imbalance (close_the_loop in app/demo_command.cpp), the simulated
  // HapticMaster plays the sensory door to its virtual user (play_and_fit_back).
  testing::TempDir dir("viewer_overlay_physical");
  const fs::path effects = dir.path / "undeclared-effect.json";
  std::ofstream(effects) << R"({"gravity_imbalance": {"g1": 3.0}})"
                         << "\n";
  const fs::path bench = dir.path / "bench.h5", played = dir.path / "played.h5";
  testing::record_built_in_session(bench, 12.0, 3, "sensory", effects);
  record_playback(played, 12.0);
  const viewer::SessionData a = viewer::load_session(bench);
  const viewer::SessionData b = viewer::load_session(played);
  const viewer::Overlay overlay = viewer::overlay_plots(a, b);

  // Angles: both the door's full range (the bench's inclinometer alone stops at its ±10°).
  const viewer::PlotView& angle = overlay_plot(overlay, "angle");
  REQUIRE(angle.series.size() == 2);
  const auto [a_low, a_high] = value_range(*angle.series[0]);
  const auto [b_low, b_high] = value_range(*angle.series[1]);
  INFO("angle: A " << a_low << " to " << a_high << ", B " << b_low << " to " << b_high << " "
                   << angle.series[0]->unit());
  CHECK(angle.series[0]->unit() == angle.series[1]->unit());
  CHECK(a_high > 60.0);
  CHECK(b_high > 60.0);
  CHECK(std::abs(a_high - b_high) < 0.2 * b_high);  // the bench's door falls open to its stop
  CHECK(std::abs(a_low) < 5.0);
  CHECK(std::abs(b_low) < 5.0);

  // Forces: opening pulls (+), closing pushes (−) in both, as export signs them.
  const viewer::PlotView& force = overlay_plot(overlay, "force");
  const viewer::PlotView& rate = overlay_plot(overlay, "rate");
  REQUIRE(force.series.size() == 2);
  REQUIRE(rate.series.size() == 2);
  const StrokeForces fa = extreme_forces(*force.series[0], *rate.series[0], 2.0);
  const StrokeForces fb = extreme_forces(*force.series[1], *rate.series[1], 2.0);
  INFO("largest force opening: A " << fa.opening_N << ", B " << fb.opening_N << "; closing: A "
                                   << fa.closing_N << ", B " << fb.closing_N);
  CHECK(fa.opening_N > 10.0);
  CHECK(fb.opening_N > 10.0);
  CHECK(fa.closing_N < -10.0);
  CHECK(fb.closing_N < -10.0);

  // Asked for, the raw channels both sessions have follow the door's three plots.
  const viewer::Overlay with_raw = viewer::overlay_plots(a, b, "", true);
  REQUIRE(with_raw.plots.size() > 3);
  CHECK(with_raw.shown == overlay.shown + " and the raw channels");
  for (std::size_t i = 0; i < with_raw.plots.size(); ++i) {
    INFO(with_raw.plots[i].title);
    CHECK((with_raw.plots[i].title.rfind("channel ", 0) == 0) == (i >= 3));
    CHECK(with_raw.plots[i].x == with_raw.plots.front().x);  // time axes linked
  }
}
