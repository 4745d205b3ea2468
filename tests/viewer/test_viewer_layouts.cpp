// A layout without its data: `view --layout NAME` fails with exit status 1
// and says what is missing, with or without --screenshot (no PNG written); with its data,
// --layout without --screenshot opens the window on that layout's tab (checked on a headless
// ImGui frame: the tab's plots are the ones drawn).
#include <catch2/catch.hpp>
#include <filesystem>

#include "acquisition/session/printable.h"
#include "acquisition/session/session_file.h"
#include "fixtures/simulated_session.h"
#include "fixtures/temp_dir.h"
#include "tests/support/run_doorbench.h"
#include "tests/support/viewer_pixels.h"
#include "viewer/session_data.h"
#include "viewer/viewer_app.h"

namespace fs = std::filesystem;
using namespace doorbench;

namespace {

// The last line of a command's stderr (before it, the viewer says which sessions have no
// strokes).
std::string last_line(const std::string& err) {
  const std::size_t end = err.size() > 0 && err.back() == '\n' ? err.size() - 1 : err.size();
  const std::size_t start = err.rfind('\n', end == 0 ? 0 : end - 1);
  return err.substr(start == std::string::npos ? 0 : start + 1);
}

}  // namespace

TEST_CASE("view --layout NAME without its data fails with exit status 1 and says why",
          "[viewer][cli]") {
  testing::TempDir dir("viewer_layouts");
  const fs::path session = dir.path / "flat.h5";
  // One flat channel: no strokes can be found in it.
  testing::write_force_session(session, std::vector<double>(300, 1.0), 100.0);
  const std::string prepare_message = viewer::load_session(session).prepare_message;
  REQUIRE_FALSE(prepare_message.empty());
  const fs::path png = dir.path / "x.png";
  const std::string shot = " --screenshot '" + png.string() + "' '" + session.string() + "'";

  auto r = testing::run_doorbench_shell("view --layout fit" + shot, dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err) ==
        "doorbench: --layout fit: No model to compare with: start the viewer with --params FILE "
        "(a fitted parameter file, e.g. the one `doorbench fit` wrote) and --model, --fit DIR "
        "or --loop DIR.\n");
  r = testing::run_doorbench_shell("view --layout steps" + shot, dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err) ==
        "doorbench: --layout steps: No residual loop: start the viewer with --loop DIR (the "
        "folder `doorbench loop` wrote).\n");
  r = testing::run_doorbench_shell("view --layout tuning" + shot, dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err) ==
        "doorbench: --layout tuning: No model to tune: start the viewer with --params FILE (or "
        "--compare, --fit DIR or --loop DIR).\n");
  r = testing::run_doorbench_shell("view --layout loop" + shot, dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err) == "doorbench: --layout loop: no strokes in " + session.string() + ": " +
                                printable(prepare_message) + "\n");
  // The window too: the check comes before any window is opened (no display needed).
  r = testing::run_doorbench_shell("view --layout fit '" + session.string() + "'", dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err).rfind("doorbench: --layout fit: No model to compare with", 0) == 0);
  CHECK_FALSE(fs::exists(png));
  // With --params, the fit layout has its model but this session has no strokes.
  r = testing::run_doorbench_shell("view --layout fit --compare" + shot, dir);
  CHECK(r.status == 1);
  CHECK(last_line(r.err) ==
        "doorbench: --layout fit: no comparison with the model: no strokes in " + session.string() +
            ": " + printable(prepare_message) + "\n");
  CHECK_FALSE(fs::exists(png));
}

TEST_CASE("the window opens on the tab --layout names", "[viewer][cli]") {
  testing::TempDir dir("viewer_initial_layout");
  const fs::path session = dir.path / "door.h5";
  testing::record_built_in_session(session, 8.0, 2, "sensory");
  std::vector<viewer::SessionData> sessions;
  sessions.push_back(viewer::load_session(session));
  REQUIRE(sessions.back().prepared);
  viewer::Viewer first(sessions, {});
  // Without a layout the window opens on the first tab (the browser: no plots).
  CHECK(testing::window_frame_plots(first).empty());
  REQUIRE(first.missing_data("loop").empty());
  viewer::Viewer on_loop(sessions, {});
  on_loop.set_initial_layout("loop");
  const auto titles = testing::window_frame_plots(on_loop);
  REQUIRE(titles.size() == 1);
  CHECK(titles[0] == "force against angle");
}
