// doorbench view: the interactive viewer (viewer/, docs/viewer.md), or one headless
// screenshot of a layout for reports and tests.
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "analysis/fit/fit_result_file.h"
#include "app/commands.h"
#include "viewer/viewer_app.h"
#include "viewer/window.h"

namespace doorbench::app {

namespace {

struct ViewOptions {
  std::vector<std::string> sessions;
  std::string screenshot;
  std::string layout;
  int width_px = 1400;
  int height_px = 900;
  bool compare = false;
  std::string loop_dir;
  std::string fit_dir;  // a `doorbench fit` output folder
  std::string live;     // a journal, or the session being recorded
  viewer::LiveOptions live_options;
  ModelOptions model;
};

// --live: follow a running recording (its journal) instead of showing sessions.
void run_live(const ViewOptions& options, const viewer::WindowOptions& window) {
  if (!options.sessions.empty()) {
    throw UsageError("--live follows one recording; give no SESSION besides it");
  }
  if (!options.layout.empty() && options.layout != "live") {
    throw UsageError("--live shows the live layout only (--layout live or none)");
  }
  if (const std::string problem = options.live_options.validate(); !problem.empty()) {
    throw UsageError("--window-s/--live-samples: " + problem);
  }
  viewer::Viewer view({}, {});
  view.set_live(std::make_unique<viewer::LiveJournal>(options.live, options.live_options));
  if (!options.screenshot.empty()) {
    viewer::screenshot(view, "live", options.screenshot, window);
    std::cout << options.screenshot << "\n" << view.live_journal()->status() << "\n";
    return;
  }
  viewer::run_window(view, window);
}

void run_view(const ViewOptions& options) {
  if (!options.live.empty()) {
    viewer::WindowOptions window;
    window.width_px = options.width_px;
    window.height_px = options.height_px;
    if (const std::string problem = window.validate(); !problem.empty()) {
      throw UsageError("--width/--height: " + problem);
    }
    run_live(options, window);
    return;
  }
  if (!options.layout.empty()) {
    const std::string problem = viewer::check_layout(options.layout);
    if (!problem.empty()) throw UsageError("--layout: " + problem);
  }
  if (!options.screenshot.empty()) {
    const std::size_t wanted = options.layout == "overlay" ? 2 : 1;
    if (options.layout != "steps" && options.sessions.size() != wanted) {
      throw UsageError(
          "--screenshot takes one SESSION (two, A and B, for --layout overlay; any for steps)");
    }
    if (options.layout.empty()) {
      throw UsageError("--screenshot needs --layout, the view to render: one of " +
                       viewer::layout_list());
    }
  }
  viewer::WindowOptions window;
  window.width_px = options.width_px;
  window.height_px = options.height_px;
  if (const std::string problem = window.validate(); !problem.empty()) {
    throw UsageError("--width/--height: " + problem);
  }
  std::optional<viewer::LoopSteps> steps;
  ModelOptions model_options = options.model;
  if (!options.loop_dir.empty()) {
    steps = viewer::read_loop_steps(options.loop_dir);
    // The loop's final model, unless a model is given.
    const std::filesystem::path dir = options.loop_dir;
    if (model_options.params_path.empty() && model_options.effects_path.empty() &&
        std::filesystem::exists(dir / "fitted-params.json")) {
      model_options.params_path = (dir / "fitted-params.json").string();
      if (std::filesystem::exists(dir / "fitted-effects.json")) {
        model_options.effects_path = (dir / "fitted-effects.json").string();
      }
    }
  }
  const bool compare =
      options.compare || !model_options.params_path.empty() || !model_options.effects_path.empty();
  std::optional<DoorModel> model;
  std::string description;
  if (!options.fit_dir.empty()) {
    // A fit result: its fitted model, of the kind result.json names.
    if (compare || !options.loop_dir.empty()) {
      throw UsageError(
          "--fit gives the model: no --params, --effects, --compare or --loop with it");
    }
    FitResultFolder fit = read_fit_result(options.fit_dir);
    description = fit.description();
    model = std::move(fit.model);
  } else if (compare) {
    model = load_model(model_options);
    description = model_options.model + " model (" +
                  (model_options.params_path.empty() ? std::string("reference door")
                                                     : model_options.params_path) +
                  ")";
  }

  std::vector<viewer::SessionData> sessions;
  std::vector<std::optional<viewer::FitComparison>> fits;
  for (const std::string& path : options.sessions) {
    sessions.push_back(viewer::load_session(path));
    if (!sessions.back().prepared) {
      std::cerr << path << ": no strokes (" << sessions.back().prepare_message << ")\n";
    }
    fits.emplace_back();
    if (model && sessions.back().prepared && !sessions.back().data.strokes.empty()) {
      fits.back() = viewer::compare_with_model(sessions.back(), *model, description);
    }
  }
  viewer::Viewer view(std::move(sessions), std::move(fits));
  if (steps) view.set_loop_steps(std::move(*steps));
  if (model) view.set_tuning_model(*model);
  if (!options.layout.empty()) {
    // A layout without its data is a failure a script can see (exit 1), not a picture of
    // the instructions.
    const std::string missing = view.missing_data(options.layout);
    if (!missing.empty()) {
      throw std::runtime_error("--layout " + options.layout + ": " + missing);
    }
    view.set_initial_layout(options.layout);
  }
  if (!options.screenshot.empty()) {
    viewer::screenshot(view, options.layout, options.screenshot, window);
    std::cout << options.screenshot << "\n";
    return;
  }
  viewer::run_window(view, window);
}

}  // namespace

void add_view_command(CLI::App& app, Action& action) {
  auto options = std::make_shared<ViewOptions>();
  CLI::App* view = app.add_subcommand(
      "view",
      "Look at sessions: metadata, channels over time, force-angle loops, measured against a "
      "model's simulation (Dear ImGui window; --screenshot renders one layout to PNG)");
  view->add_option("SESSION", options->sessions, "Session files (HDF5)")->check(CLI::ExistingFile);
  view->add_option("--screenshot", options->screenshot,
                   "Render --layout of the one SESSION offscreen to this PNG and exit (also "
                   "writes PNG.json: where each plot is and its ranges)");
  view->add_option("--layout", options->layout,
                   "browser, channels, loop, fit, overlay, steps or tuning: what --screenshot "
                   "renders, or the tab the window opens on; exit 1 when it lacks its data "
                   "(no model for fit, no --loop for steps, ...)");
  view->add_option("--width", options->width_px, "Window width in pixels")->capture_default_str();
  view->add_option("--height", options->height_px, "Window height in pixels")
      ->capture_default_str();
  view->add_option("--loop", options->loop_dir,
                   "A `doorbench loop` folder: its steps (layout steps) and its final model "
                   "for the fit layout (unless --params/--effects say otherwise)")
      ->check(CLI::ExistingDirectory);
  view->add_option("--fit", options->fit_dir,
                   "A `doorbench fit` folder: its fitted model (result.json, fitted-params.json, "
                   "fitted-effects.json) for the fit and tuning layouts")
      ->check(CLI::ExistingDirectory);
  view->add_option("--live", options->live,
                   "Follow a running recording: its journal (S.h5.journal) or the session it "
                   "records (S.h5); the channels scroll as they arrive");
  view->add_option("--window-s", options->live_options.window_s,
                   "--live: seconds of the recording shown")
      ->capture_default_str();
  view->add_option("--live-samples", options->live_options.capacity_samples,
                   "--live: samples kept per channel (older ones are dropped)")
      ->capture_default_str();
  view->add_flag("--compare", options->compare,
                 "Compare each session with the model (implied by --params or --effects)");
  add_model_options(*view, options->model);
  view->callback([options, &action] { action = [options] { run_view(*options); }; });
}

}  // namespace doorbench::app
