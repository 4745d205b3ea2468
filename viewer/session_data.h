#pragma once
// What the viewer shows of one session (no GL, no ImGui): metadata, channels as physical
// values over time, events, calibration records; the force–angle loop split by stroke
// direction; and, given a door model (a fitted parameter file), the measured rate against
// the model's simulation with the residual.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "acquisition/session/session_file.h"
#include "analysis/fit/residual_whiteness.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"
#include "analysis/report/plot_style.h"
#include "viewer/plot_view.h"

namespace doorbench::viewer {

// Distinct colours for series, in order; index wraps.
Rgba palette(std::size_t index);
// The colour of a meaning (analysis/report/plot_style.h, shared with the SVG reports), with the
// viewer's opacity as alpha unless `opaque`.
Rgba meaning_colour(plot_style::Meaning meaning, bool opaque = false);
// Colour, width and layer of a curve from its meaning: measured on top, a model's curve
// wide and translucent under it.
void style_series(Series& series, plot_style::Meaning meaning);
// The viewer keeps every quantity in its stored unit until it makes a curve of it; here the
// values are put in the unit people read (plot_style::display_unit, the one place that says
// which: rad -> deg, rad/s -> deg/s, as the SVG reports show them): `values` scaled in place
// (NaN stays NaN), the unit shown returned. The curve's header then names that unit.
std::string to_display_units(const std::string& stored_unit, std::vector<double>& values);

struct SessionData {
  std::filesystem::path path;
  SessionMetadata metadata;
  std::vector<ChannelInfo> channels;
  std::vector<std::size_t> sample_counts;
  // The file's events in time order. A session without stroke_start events (a haptic
  // playback's) gets them here on read when its strokes were prepared: one stroke_start and
  // one stroke_end per prepared stroke (found from the motion as preprocessing segments,
  // detail "opening" or "closing", no channel) at motion_onset_s / motion_end_s.
  std::vector<SessionEvent> events;
  bool strokes_found_on_read = false;
  std::vector<CalibrationRecord> calibrations;
  // Per channel (same order): physical values over session time, in the unit shown
  // (to_display_units: an angle in deg, a rate in deg/s).
  std::vector<std::shared_ptr<Series>> channel_series;
  // Per channel (same order): its stretches at its sensor's limit (sensors/channel_limits.h,
  // the rig the session states: record's definition), as shades over [the first sample at the
  // limit, the sample after the last); empty for a channel without a known limit.
  std::vector<std::vector<Shade>> at_limit;

  // The session prepared into strokes (analysis/preprocessing/preprocessing.h); when that fails,
  // prepared is false and prepare_message says why (the views that need strokes say so).
  bool prepared = false;
  std::string prepare_message;
  PreparedData data;
  // The door's physical quantities read off the prepared strokes, on the session clock, the
  // strokes separated by NaN (empty when not prepared): door_angle the door's angle as
  // preprocessing fuses it (inclinometer and gyroscope) in deg, door_force the hand force
  // at the handle signed as `export` signs it (positive opening, the load cell's mounting
  // applied) in N, door_rate the rate (bias removed) in deg/s. A bench's raw channels are a
  // sensor's view (an inclinometer flat at its ±10° range, a compression-only load cell);
  // these compare with a haptic playback's like for like.
  std::shared_ptr<Series> door_angle, door_force, door_rate;
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
// measured start (what a fit compares: analysis/fit/fit_metrics.h), and the residual ω − ω̂;
// strokes one after the other on the session clock, separated by NaN.
struct FitComparison {
  std::string model_description;
  std::shared_ptr<Series> measured;
  std::shared_ptr<Series> simulated;
  std::shared_ptr<Series> residual;
  double rmse_rad_s = 0.0;
  // The residual's autocorrelation and its cross-correlation with the force, strokes kept
  // apart, lags up to 0.5 s (analysis/fit/residual_whiteness.h); empty when it cannot be
  // computed (whiteness_message says why).
  std::optional<ResidualWhiteness> whiteness;
  std::string whiteness_message;
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

// Where a prepared stroke's motion starts and ends: its first and last sample with |ω|
// above preprocessing's motion threshold (PreprocessingOptions::motion_rate_rad_s); the
// stroke's first and last sample when none is.
double motion_onset_s(const Stroke& stroke);
double motion_end_s(const Stroke& stroke);
// The motion onset of the session's first prepared stroke of `direction` ("" any).
// Throws std::invalid_argument naming the session when it has none (with why).
double first_motion_onset_s(const SessionData& session, const std::string& direction = "");

// The A/B overlay: A's and B's series on time since their first stroke start (of
// `direction`), so that the strokes line up. When both sessions were prepared into strokes,
// the door's physical quantities (SessionData::door_angle, door_force, door_rate: plots
// titled "angle: ...", "force: ...", "rate: ...") — a bench recording and its haptic
// playback then show the same quantities in one sign convention; the raw channels both
// sessions have (by name, plots titled "channel NAME: ...") follow when `raw_channels` is
// set, and are all that is shown when either session is not prepared (`shown` says why).
// Both sessions are aligned the same way: on their first stroke_start event when both files
// carry stroke events, else (one of them is e.g. a haptic playback, whose strokes are found
// on read) on both first strokes' motion onset. A is drawn as measured on top, B under it.
struct Overlay {
  double a_start_s = 0.0, b_start_s = 0.0;  // the stroke starts aligned to 0
  std::string alignment;                    // "stroke_start events" or "motion onset"
  // What the plots show: "the door's angle (fused ...), hand force (+ opening ...) and rate,
  // from the prepared strokes", with " and the raw channels" when asked, or "raw channels: NAME is
  // not prepared into strokes (why)" when a session was not prepared.
  std::string shown;
  std::vector<PlotView> plots;  // time axes linked
};
Overlay overlay_plots(const SessionData& a, const SessionData& b, const std::string& direction = "",
                      bool raw_channels = false);

// The group a channel is shown in, by its sensor kind: a haptic playback's channels
// (haptic/tick_recorder.cpp) as "door" (force, angle, rate: what a fit reads), "device"
// (position, velocity, measured and commanded force), "model" (model torque and its
// terms) and "safety" (passivity, constraint errors, safety scale, parameter set); ""
// for any other (a bench's sensors: one group, no headers).
std::string channel_group(const ChannelInfo& channel);
// The groups in the order they are shown.
inline const std::vector<std::string>& channel_group_order() {
  static const std::vector<std::string> order = {"door", "device", "model", "safety", ""};
  return order;
}

// A plot of each channel over time, their time axes linked to the first.
std::vector<PlotView> channel_plots(const SessionData& session);
// Force against angle, opening and closing in their colours (empty series: not prepared).
PlotView loop_plot(const SessionData& session);
// Measured and simulated ω, the residual below with its time axis linked, and (when
// computed) the residual's whiteness: autocorrelation and cross-correlation with the force
// against the lag, with the 99 % band.
std::vector<PlotView> fit_plots(const FitComparison& comparison);
// The whiteness plot: autocorrelation (lags ≥ 0) and cross-correlation with the force
// (lags of either sign) against the lag in s, and the ±99 % band.
PlotView whiteness_plot(const ResidualWhiteness& whiteness);

}  // namespace doorbench::viewer
