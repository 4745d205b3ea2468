#pragma once
// Preprocessing (door-models.md §5): a recording (CSV exchange format, or a session through
// session_to_recording) becomes PreparedData (analysis/preprocessing/strokes.h): opening and
// closing strokes with the full-range angle, the rate with its bias removed and the handle force,
// plus the segments left out and the noise levels. The method, every constant and the
// measured accuracy are in docs/preprocessing.md.
//
// The angle, by what the recording holds:
//   rate_rad_s + an inclinometer column (narrow range, lagging; e.g. inclinometer_angle_rad):
//     the gyroscope's rate, its bias removed, integrated (trapezoid) and anchored to the
//     inclinometer at still periods where it is in range; the drift between anchors is
//     removed piecewise-linearly (so each interval between anchors gets its own bias).
//   rate_rad_s + angle_rad (full range): θ = angle_rad; ω = the rate with its bias removed,
//     the bias taken from angle_rad the same way.
//   angle_rad only: θ = angle_rad; ω = the derivative of angle_rad after a zero-phase
//     (forward-backward) low-pass.
//   rate_rad_s only: the integrated rate, with θ = 0 at the first still period (taken for
//     the closed door); PreparedData::notes says so.
// Strokes: the stroke column when present (ids kept), else motion segments; each stroke's
// direction is the sign of its net angle change. Strokes with a saturated gyroscope,
// non-finite values or a gap in time are left out and listed, as are strokes too short to
// be one.
//
// Thread safety: free functions without shared state.
#include <filesystem>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "acquisition/session/recording_csv.h"
#include "analysis/preprocessing/strokes.h"
#include "core/units.h"

namespace doorbench {

// Bad input data (what is missing, not enough of it): the message starts with the source.
class PreprocessingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Every option has a usable default (the reference bench, door-models.md §5); angles in
// rad, rates in rad/s, times in s.
struct PreprocessingOptions {
  // Stillness test. A sample is quiet when, over the centred window of still_window_s,
  // the rate's standard deviation is below max(still_noise_factor × σ̂, still_rate_std_floor)
  // (σ̂: the rate's white noise, estimated robustly from the whole recording), the rate's
  // mean magnitude is below still_rate_limit (the gyroscope's bias is inside the mean:
  // this bounds it), the mean |force| is below still_force_N, and no sample is faulty.
  // A still period is a run of quiet samples, less still_guard_s at both ends (a motion
  // that starts gently stays below the noise test for tens of ms), lasting at least
  // still_min_duration_s. The window is never shorter than kStillWindowSamples samples
  // (at 50 Hz: 0.2 s), so that its standard deviation means something at low rates.
  double still_window_s = 0.1;
  double still_min_duration_s = 0.3;
  double still_guard_s = 0.1;
  double still_noise_factor = 3.0;
  double still_rate_std_floor_rad_s = 0.02 * kRadPerDeg;
  double still_rate_limit_rad_s = 1.0 * kRadPerDeg;
  double still_force_N = 2.0;
  // Rate only: still periods whose mean rate differs from the median of all still
  // periods' by more than this are not used for the bias (a door creeping to rest).
  double bias_consistency_rad_s = 0.1 * kRadPerDeg;

  // Gyroscope: samples with |rate| >= (1 − gyro_saturation_fraction) × gyro_range_rad_s
  // are saturated; a stroke holding one is left out.
  double gyro_range_rad_s = 100.0 * kRadPerDeg;
  double gyro_saturation_fraction = 0.01;

  // Inclinometer: the extra column to use ("" = the first whose name starts with
  // "inclinometer" and ends in _rad or _deg). It anchors the integrated rate only where
  // |angle| < inclinometer_range_rad − inclinometer_margin_rad (beyond, it saturates),
  // from inclinometer_settle_s after a still period starts (its low-pass has settled:
  // 0.1 s is 6 time constants of the bench's 10 Hz filter).
  std::string inclinometer_column;
  double inclinometer_range_rad = 10.0 * kRadPerDeg;
  double inclinometer_margin_rad = 0.5 * kRadPerDeg;
  double inclinometer_settle_s = 0.1;

  // Zero-phase (forward-backward 2nd-order Butterworth) low-pass filters, −6 dB at the
  // cut-off: before differentiating angle_rad (when there is no rate), and optionally on
  // the force (0 = off, the default: the door's inertia already averages the load cell's
  // noise, and a filter would round the latch's force edges). derivative_cutoff_hz 0 (the
  // default) follows the sample rate f_s: auto_derivative_cutoff_hz(f_s) = min(30 Hz,
  // f_s / 4). A cut-off given must be below f_s / 2 (else PreprocessingError).
  double derivative_cutoff_hz = 0.0;
  double force_cutoff_hz = 0.0;

  // Recordings sampled more slowly than this (1 / the median interval) are refused: the
  // rate rules (docs/preprocessing.md, "Any sample rate") are made and tested down to 20 Hz.
  double min_sample_rate_hz = 20.0;

  // Segmentation (used when there is no stroke column, or use_stroke_column is false):
  // motion where |ω| > motion_rate_rad_s, widened while |ω| stays above
  // max(edge_rate_rad_s, 4 × rate noise) in the same direction; segments less than
  // merge_gap_s apart merge when they move the same way (or one of them moves less than
  // min_stroke_angle_rad); each stroke gets stroke_margin_s of the rest before and after
  // it (never beyond its neighbours), so that it starts from its initial state at rest.
  bool use_stroke_column = true;
  double motion_rate_rad_s = 2.0 * kRadPerDeg;
  double edge_rate_rad_s = 0.2 * kRadPerDeg;
  double merge_gap_s = 0.3;
  double stroke_margin_s = 0.1;
  // Strokes (from the column or found) shorter than this, or moving less, are left out.
  double min_stroke_duration_s = 0.2;
  double min_stroke_angle_rad = 1.0 * kRadPerDeg;

  // An interval between samples longer than max_gap_factor × the median interval is a
  // gap in time_s (a jump of the clock).
  double max_gap_factor = 10.0;
  // Scans lost in recording (rows where every measured column is missing) and gaps in
  // time_s: a stroke holding one keeps its samples on both sides (Stroke::gap_before) when
  // its angle is known on both, and the fit leaves out the windows that span the gap; else
  // its longest gap-free part is kept. Every gap is listed in PreparedData::excluded. A gap
  // lasting at most max_bridged_loss_s (from the last sample before to the first after) is
  // bridged for the angle: the rate interpolated across it stands in, so the drift between
  // the anchors around it is still removed and the angle is known on both sides; a longer
  // one makes the rate unknown there, as any fault does. 0: never bridged.
  double max_bridged_loss_s = 0.05;

  // Physically impossible samples: a value beyond these limits (or, for the rate and the
  // inclinometer, beyond impossible_factor × the sensor's range: no reading of that sensor
  // can be there) is not a measurement. It is left out like a non-finite value (a stroke
  // holding one keeps its longest good part) and PreparedData::warnings names the channel,
  // the count, the first time and the largest value. 10 kN is fifty times what a hand
  // pushes on a door; 2π rad is a whole turn of a door that opens 90°.
  double max_abs_force_N = 1e4;
  double max_abs_angle_rad = 2.0 * std::numbers::pi;
  double impossible_factor = 10.0;

  // Noise levels when there is no still period to estimate them from: the reference
  // bench's inclinometer (0.01°) and gyroscope (0.05 °/s). Estimates never go below 1% of
  // these (a noise-free simulated recording would otherwise give zero).
  double fallback_angle_noise_rad = 0.01 * kRadPerDeg;
  double fallback_rate_noise_rad_s = 0.05 * kRadPerDeg;

  // "" when usable, else one line naming the first bad option.
  std::string validate() const;
};

// The still window's least number of samples (PreprocessingOptions::still_window_s).
inline constexpr int kStillWindowSamples = 10;
// Intervals that differ from 1 / the sample rate by more than this fraction make the
// times jittered: the filters then work on a uniform grid (zero_phase_lowpass_at).
inline constexpr double kJitterFraction = 0.01;
// Below this rate the latch's details (its release, snap and force edges last a few
// milliseconds on the reference door) are not resolved; PreparedData::rate_summary says so.
inline constexpr double kLatchDetailRate_hz = 200.0;

// The derivative's cut-off for a sample rate: min(30 Hz, f_s / 4). 30 Hz is the bench's
// measured best at 1 kHz (docs/preprocessing.md); f_s / 4 keeps the filter well inside
// the band the samples hold (half of Nyquist) at low rates: 12.5 Hz at 50 Hz, 5 Hz at 20 Hz.
double auto_derivative_cutoff_hz(double sample_rate_hz);

// Prepares a recording. Throws std::invalid_argument for bad options and
// PreprocessingError (message "SOURCE: ...") for data it cannot prepare: no samples or
// too few, columns of different lengths, times not finite and increasing, neither rate
// nor angle, no still period to anchor the gyroscope to (or, rate only, to start from).
PreparedData prepare(const Recording& recording, const PreprocessingOptions& options = {});

// Reads a session (SessionReader + session_to_recording) and prepares it.
PreparedData prepare_session(const std::filesystem::path& session_path,
                             const PreprocessingOptions& options = {});

// Building blocks (also used by prepare).

// Zero-phase low-pass: a 2nd-order Butterworth (bilinear, pre-warped) run forward then
// backward, on samples `sample_rate_hz` apart; the ends are padded by odd reflection and
// the filter starts in its steady state, so a constant or a straight line passes
// unchanged. Gain 1/2 (−6 dB) at cutoff_hz, no phase shift. cutoff_hz must be below half
// the sample rate.
std::vector<double> zero_phase_lowpass(std::span<const double> values, double cutoff_hz,
                                       double sample_rate_hz);

// zero_phase_lowpass of samples taken at `time_s` (strictly increasing), which need not be
// uniform: when an interval differs from 1 / sample_rate_hz by more than kJitterFraction,
// the values are interpolated linearly onto the uniform grid time_s[0] + k / sample_rate_hz,
// filtered there and interpolated back to time_s; otherwise this is zero_phase_lowpass.
std::vector<double> zero_phase_lowpass_at(std::span<const double> time_s,
                                          std::span<const double> values, double cutoff_hz,
                                          double sample_rate_hz);

// The derivative of zero_phase_lowpass(values): central differences on the times
// (one-sided at the ends). Jittered times (as for zero_phase_lowpass_at): the derivative is
// taken on the uniform grid and interpolated back to time_s.
std::vector<double> smoothing_derivative(std::span<const double> time_s,
                                         std::span<const double> values, double cutoff_hz,
                                         double sample_rate_hz);

}  // namespace doorbench
