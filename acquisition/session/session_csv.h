#pragma once
// Between sessions and the CSV exchange format (door-models.md §5.1).
//
// Export maps channels by unit: the first channel in N gives force_N (a compression-only
// load cell's reading signed by each stroke's mounting: + on openings, − on closings),
// the first in rad/s gives rate_rad_s, the first in rad that is not an inclinometer gives
// angle_rad; every other channel (the narrow-range inclinometer among them) becomes an
// extra column <name>_<unit> (prefixed with its sensor kind if that would take a main
// column's name: the inclinometer "angle" gives inclinometer_angle_rad). When all exported
// channels share one uniform clock, the time column is the force channel's (converter skews of
// a few µs are not resampled). Otherwise (polled channels with explicit times, other rates)
// every channel is linearly interpolated onto the force channel's clock (if uniform; else the
// first uniform channel's; else 1 / the force channel's median interval), only where every
// channel has samples, and times inside a channel's gap (> 3 of its median intervals) are
// left out; metadata "resampled" and "resample_gaps" say so (docs/synchronization.md).
// Strokes come from stroke_start/stroke_end events.
//
// A channel whose calibration record states a delay (delay_s, a lagging inclinometer) is
// shifted back by it on export, so that every column describes the same instant.
//
// A load cell whose channel names a geometry record (geometry_calibration_id) has its force
// corrected by it (the record maps the reading to the tangential force: / cos of the
// mounting angle), and the record's handle_radius_m becomes the recording's handle radius
// (before the truth's, the import's or the haptic playback's); the metadata key
// geometry_calibration names it.
//
// Import makes a session of a recording: one float64 channel per column, in the column's
// unit, with no calibration (the values already are physical); times become a sample
// clock only when that clock gives every time back exactly, else they are stored as
// explicit times; strokes become events that keep their ids; the CSV's metadata lines
// are kept as attributes of the session's "import" group; channel_names (kChannelNamesKey)
// gives each column's channel name back (without it: force, angle, rate, and extra columns
// by their column name). A column whose name starts with
// "inclinometer" becomes an inclinometer channel (narrow range, not the door angle).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "acquisition/session/recording_csv.h"
#include "acquisition/session/session_file.h"

namespace doorbench {

// The metadata key that names the geometry record applied to the force (export adds it).
inline constexpr std::string_view kGeometryCalibrationKey = "geometry_calibration";
// The metadata key naming each column's channel, "force_N=force,inclinometer_angle_rad=angle"
// (export adds it; import names the channels so, so that a round trip keeps their names).
inline constexpr std::string_view kChannelNamesKey = "channel_names";

// The metadata key session_to_recording adds when a channel ends before the others on the
// same clock: "force from 3 s (3000 of 6000 rows)" (its cells are missing from there).
inline constexpr std::string_view kCutShortKey = "cut_short";

Recording session_to_recording(const SessionReader& session);

// Per sample of `time_s`: the stroke it belongs to (0: none) and the load cell's mounting
// (+1 opening, −1 closing), from stroke_start/stroke_end events (any order). An event
// applies from the sample at its time (within a part in 1e9). A stroke_start whose detail
// is "stroke N" (N > 0) keeps id N, others are numbered on from the last; its detail
// "opening" or "closing" sets the mounting until the next such detail.
struct StrokeColumns {
  std::vector<int> stroke;
  std::vector<int> sign;
  bool any_stroke = false;  // a stroke_start applied to some sample
};
StrokeColumns stroke_columns_from_events(std::vector<SessionEvent> events,
                                         const std::vector<double>& time_s);

// Writes `recording` as a new session at `path` (which must not exist).
void recording_to_session(const Recording& recording, const std::filesystem::path& path,
                          const SessionMetadata& metadata);

}  // namespace doorbench
