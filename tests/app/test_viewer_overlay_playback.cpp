// The A/B overlay of the real door and its haptic playback (issue 21, item 1): a bench
// session (the simulated bench, stroke events recorded) and a playback session (the
// simulated HapticMaster's render loop, no stroke events) are overlaid by the real
// `doorbench view --screenshot` under Xvfb; both rate curves must be in the picture and
// leave rest at the same place, the aligned stroke start.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <map>

#include "analysis/model/parameter_file.h"
#include "haptic/device_factory.h"
#include "haptic/playback.h"
#include "tests/support/simulated_session.h"
#include "tests/support/temp_dir.h"
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
  const auto& plot = shot.plot("rate:");
  REQUIRE(plot["series"].size() == 2);
  const std::vector<int> rgb_a = plot["series"][0]["rgb"], rgb_b = plot["series"][1]["rgb"];
  const testing::PlotGeometry g(plot);
  REQUIRE(g.xmin < -0.5);  // rest before the stroke is in view
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
