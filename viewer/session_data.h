#pragma once
// What the viewer shows of one session (no GL, no ImGui): metadata, channels as physical
// values over time, events, calibration records; the force–angle loop split by stroke
// direction; and, given a door model (a fitted parameter file), the measured rate against
// the model's simulation with the residual.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "acquisition/session_file.h"
#include "analysis/door_model.h"
#include "analysis/strokes.h"
#include "viewer/plot_view.h"

namespace doorbench::viewer {

// Distinct colours for series, in order; index wraps.
Rgba palette(std::size_t index);
inline constexpr Rgba kOpeningColour{230, 90, 40, 255};   // orange-red
inline constexpr Rgba kClosingColour{40, 140, 230, 255};  // blue

struct SessionData {
  std::filesystem::path path;
  SessionMetadata metadata;
  std::vector<ChannelInfo> channels;
  std::vector<std::size_t> sample_counts;
  std::vector<SessionEvent> events;
  std::vector<calibration::CalibrationRecord> calibrations;
  // Per channel (same order): physical values over session time, in the channel's unit.
  std::vector<std::shared_ptr<Series>> channel_series;

  // The session prepared into strokes (analysis/preprocessing.h); when that fails,
  // prepared is false and prepare_message says why (the views that need strokes say so).
  bool prepared = false;
  std::string prepare_message;
  PreparedData data;
  // Handle force against angle, one series per direction, strokes separated by NaN.
  std::shared_ptr<Series> opening_loop;
  std::shared_ptr<Series> closing_loop;
};

struct LoadOptions {
  bool prepare = true;  // also prepare strokes (loop and fit views)
};

// Reads the whole session into memory. Throws SessionError for the file.
SessionData load_session(const std::filesystem::path& path, const LoadOptions& options = {});

// Measured ω against the model's ω̂, simulated window by window from each window's
// measured start (what a fit compares: analysis/fit_metrics.h), and the residual ω − ω̂;
// strokes one after the other on the session clock, separated by NaN.
struct FitComparison {
  std::string model_description;
  std::shared_ptr<Series> measured;
  std::shared_ptr<Series> simulated;
  std::shared_ptr<Series> residual;
  double rmse_rad_s = 0.0;
};
// Throws std::invalid_argument when the session has no prepared strokes.
FitComparison compare_with_model(const SessionData& session, const DoorModel& model,
                                 const std::string& description);

// The session's events as markers on a time axis: triggers, strokes, faults, gaps and
// marks, for the whole session or for `channel` ("" : whole-session events only).
std::vector<Marker> event_markers(const SessionData& session, const std::string& channel);
// The same for any list of events (a live recording's); also `stop` (red).
template <typename Events>
std::vector<Marker> event_markers_of(const Events& events, const std::string& channel);
// The marker of one event, or false for kinds that are not marked.
bool event_marker(const SessionEvent& event, Marker& marker);
template <typename Events>
std::vector<Marker> event_markers_of(const Events& events, const std::string& channel) {
  std::vector<Marker> markers;
  Marker marker;
  for (const SessionEvent& e : events) {
    if (!e.channel.empty() && e.channel != channel) continue;
    if (event_marker(e, marker)) markers.push_back(marker);
  }
  return markers;
}

// The time of the first stroke_start event of `direction` ("opening", "closing"; "" any).
// Throws std::invalid_argument naming the session when there is none.
double first_stroke_start_s(const SessionData& session, const std::string& direction = "");

// The A/B overlay: for each channel both sessions have (by name), A's and B's series on
// time since their first stroke start (of `direction`), so that the strokes line up.
struct Overlay {
  double a_start_s = 0.0, b_start_s = 0.0;  // the stroke starts aligned to 0
  std::vector<PlotView> plots;              // time axes linked
};
Overlay overlay_plots(const SessionData& a, const SessionData& b,
                      const std::string& direction = "");

// A plot of each channel over time, their time axes linked to the first.
std::vector<PlotView> channel_plots(const SessionData& session);
// Force against angle, opening and closing in their colours (empty series: not prepared).
PlotView loop_plot(const SessionData& session);
// Measured and simulated ω, and the residual below with its time axis linked.
std::vector<PlotView> fit_plots(const FitComparison& comparison);

}  // namespace doorbench::viewer
