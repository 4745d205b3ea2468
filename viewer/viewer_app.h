#pragma once
// The viewer's views and layouts on ImGui (no window: viewer/window.h runs them):
//   browser   the session's metadata, channels, events, calibration records, strokes
//   channels  every channel over time, time axes linked
//   loop      force against angle, opening and closing strokes in their colours
//   fit       measured rate against a door model's simulation, the residual below
//   overlay   A/B: the first two sessions' door angle, force and rate (their raw channels
//             on request) aligned on their first stroke
//   steps     the residual loop's steps (a `doorbench loop` folder): error before and after
//   tuning    sliders for the model's parameters and perceptual controls; strokes replayed
// The interactive window shows them as tabs with a session selector; a screenshot shows
// one layout over the whole window.
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "viewer/live_journal.h"
#include "viewer/loop_steps.h"
#include "viewer/plot_widget.h"
#include "viewer/session_data.h"
#include "viewer/tuning.h"

namespace doorbench::viewer {

inline const std::vector<std::string>& layout_names() {
  static const std::vector<std::string> names = {"browser", "channels", "loop",  "fit",
                                                 "overlay", "steps",    "tuning"};
  return names;
}

// The layouts for messages: "browser, channels, loop, fit, overlay, steps, tuning".
std::string layout_list();

class Viewer {
 public:
  // fits[i] (optional) compares session i with a model.
  Viewer(std::vector<SessionData> sessions, std::vector<std::optional<FitComparison>> fits);

  // Builds one frame's ImGui windows over a display of width × height pixels: the layout
  // named (one of layout_names()), or every layout as tabs when it is empty. Between
  // ImGui::NewFrame() and ImGui::Render(). Throws std::invalid_argument for an unknown name.
  void frame(float width, float height, const std::string& layout = "");
  // "" when `layout` has what it shows for the current session, else why not (the text the
  // layout shows instead): loop needs prepared strokes, fit a model compared with the
  // session, overlay two sessions aligned, steps a loop folder, tuning a model and strokes.
  // Browser and channels always have it. Throws std::invalid_argument for an unknown name.
  std::string missing_data(const std::string& layout) const;
  // The tab the interactive window shows first ("" : the first tab).
  void set_initial_layout(std::string layout) { initial_layout_ = std::move(layout); }
  // The plots drawn in the last frame.
  const std::vector<PlotRecord>& plots() const { return plots_; }
  std::size_t session_count() const { return sessions_.size(); }
  void set_loop_steps(LoopSteps steps);
  // The model the tuning layout starts from (the fitted one).
  void set_tuning_model(DoorModel model) { tuning_model_ = std::move(model); }

  // Export: a plot's CSV button writes its visible data to export_dir at once; its PNG
  // button leaves a request that the window fulfils after rendering the frame.
  std::filesystem::path export_dir = ".";
  struct PngRequest {
    Rect rect;  // in display pixels
    std::filesystem::path path;
  };
  std::optional<PngRequest> take_png_request();
  void set_status(std::string status) { status_ = std::move(status); }
  // Live: follow a running recording's journal instead of showing sessions; every frame
  // polls it and the channels scroll (the `live` layout).
  void set_live(std::unique_ptr<LiveJournal> live) { live_ = std::move(live); }
  const LiveJournal* live_journal() const { return live_.get(); }

 private:
  struct SessionView {
    SessionData data;
    std::vector<PlotView> channels;
    PlotView loop;
    std::optional<FitComparison> fit;
    std::vector<PlotView> fit_plots;
    std::vector<PlotWidgetState> channel_states;
    PlotWidgetState loop_state;
    std::vector<PlotWidgetState> fit_states;
    std::optional<Tuning> tuning;  // made when the tuning layout is first shown
    std::string tuning_message;
    PlotWidgetState tuning_state;
  };
  void browser(SessionView& s);
  void channels(SessionView& s);
  void loop(SessionView& s);
  void fit(SessionView& s);
  void overlay();
  void steps();
  void tuning(SessionView& s);
  void layout_body(SessionView& s, const std::string& layout);

  std::vector<SessionView> sessions_;
  int current_ = 0;
  std::string initial_layout_;
  bool initial_layout_shown_ = false;
  std::optional<Overlay> overlay_;
  std::string overlay_message_;
  std::vector<PlotWidgetState> overlay_states_;
  bool overlay_raw_ = false;  // the overlay shows the raw channels too (its checkbox)
  void make_overlay();
  std::optional<LoopSteps> steps_;
  PlotView steps_plot_;
  PlotWidgetState steps_state_;
  std::optional<DoorModel> tuning_model_;
  char save_path_[512] = "tuned-params.json";
  bool controls_ = false;  // export buttons (interactive window only)
  std::optional<PngRequest> png_request_;
  std::string status_;
  int exports_ = 0;
  void handle_exports();
  std::filesystem::path export_path(const std::string& title, const std::string& extension);
  std::vector<PlotRecord> plots_;
  void live();
  std::unique_ptr<LiveJournal> live_;
  std::vector<PlotView> live_plots_;
  std::vector<PlotWidgetState> live_states_;
  std::chrono::steady_clock::time_point live_rebuilt_{};
};

// Checks a layout name: "" when known, else a message listing the names.
std::string check_layout(const std::string& name);

}  // namespace doorbench::viewer
