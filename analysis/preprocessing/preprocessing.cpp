// prepare() (docs/preprocessing.md): the options validated, the stages run in order
// (internal/prepare_stages.h), and what the prepared data says about its source, its rate
// and how the angle was obtained.
#include "analysis/preprocessing/preprocessing.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>

#include "acquisition/session/session_csv.h"
#include "acquisition/session/session_file.h"
#include "analysis/preprocessing/internal/prepare_stages.h"
#include "core/number_format.h"
#include "core/units.h"

namespace doorbench {

using namespace preprocessing_detail;

std::string PreprocessingOptions::validate() const {
  struct Rule {
    const char* name;
    double value;
    bool strictly_positive;  // else >= 0
  };
  const Rule rules[] = {
      {"still_window_s", still_window_s, true},
      {"still_min_duration_s", still_min_duration_s, true},
      {"still_guard_s", still_guard_s, false},
      {"still_noise_factor", still_noise_factor, true},
      {"still_rate_std_floor_rad_s", still_rate_std_floor_rad_s, false},
      {"still_rate_limit_rad_s", still_rate_limit_rad_s, true},
      {"still_force_N", still_force_N, true},
      {"bias_consistency_rad_s", bias_consistency_rad_s, true},
      {"gyro_range_rad_s", gyro_range_rad_s, true},
      {"gyro_saturation_fraction", gyro_saturation_fraction, false},
      {"inclinometer_range_rad", inclinometer_range_rad, true},
      {"inclinometer_margin_rad", inclinometer_margin_rad, false},
      {"inclinometer_settle_s", inclinometer_settle_s, false},
      {"derivative_cutoff_hz", derivative_cutoff_hz, false},
      {"min_sample_rate_hz", min_sample_rate_hz, true},
      {"force_cutoff_hz", force_cutoff_hz, false},
      {"motion_rate_rad_s", motion_rate_rad_s, true},
      {"edge_rate_rad_s", edge_rate_rad_s, false},
      {"merge_gap_s", merge_gap_s, false},
      {"stroke_margin_s", stroke_margin_s, false},
      {"min_stroke_duration_s", min_stroke_duration_s, false},
      {"min_stroke_angle_rad", min_stroke_angle_rad, false},
      {"max_gap_factor", max_gap_factor, true},
      {"max_bridged_loss_s", max_bridged_loss_s, false},
      {"max_abs_force_N", max_abs_force_N, true},
      {"max_abs_angle_rad", max_abs_angle_rad, true},
      {"impossible_factor", impossible_factor, true},
      {"fallback_angle_noise_rad", fallback_angle_noise_rad, true},
      {"fallback_rate_noise_rad_s", fallback_rate_noise_rad_s, true},
  };
  for (const Rule& rule : rules) {
    const std::string head =
        std::string("preprocessing ") + rule.name + " = " + format_number(rule.value) + " must be ";
    if (!std::isfinite(rule.value)) return head + "finite";
    if (rule.strictly_positive && !(rule.value > 0)) return head + "> 0";
    if (!rule.strictly_positive && !(rule.value >= 0)) return head + ">= 0";
  }
  if (gyro_saturation_fraction >= 1) {
    return "preprocessing gyro_saturation_fraction = " + format_number(gyro_saturation_fraction) +
           " must be < 1";
  }
  if (inclinometer_margin_rad >= inclinometer_range_rad) {
    return "preprocessing inclinometer_margin_rad = " + format_number(inclinometer_margin_rad) +
           " must be < inclinometer_range_rad = " + format_number(inclinometer_range_rad);
  }
  if (edge_rate_rad_s > motion_rate_rad_s) {
    return "preprocessing edge_rate_rad_s = " + format_number(edge_rate_rad_s) +
           " must be <= motion_rate_rad_s = " + format_number(motion_rate_rad_s);
  }
  if (max_gap_factor <= 1) {
    return "preprocessing max_gap_factor = " + format_number(max_gap_factor) + " must be > 1";
  }
  return "";
}

namespace {

std::string milliseconds(double value_s) {
  return text(1000.0 * value_s) + " ms";
}

// PreparedData::rate_summary: the rate, its jitter, the derivative's cut-off, and what the
// rate does not resolve (docs/preprocessing.md, "Any sample rate").
std::string describe_rate(const Input& in, double derivative_cutoff_hz, bool cutoff_auto) {
  std::string line = "sample rate " + text(in.rate_hz) + " Hz (median interval " +
                     milliseconds(in.median_interval_s);
  if (in.jittered) {
    line += ", intervals " + milliseconds(in.min_interval_s) + " to " +
            milliseconds(in.max_interval_s) + ": jittered, filtered on a uniform " +
            milliseconds(in.median_interval_s) + " grid";
  }
  line += ")";
  double resolved_hz = 0.5 * in.rate_hz;
  if (derivative_cutoff_hz > 0) {
    line += "; the rate is angle_rad's derivative, low-passed at " + text(derivative_cutoff_hz) +
            " Hz" + (cutoff_auto ? " (min(30 Hz, rate / 4))" : " (as asked)");
    resolved_hz = derivative_cutoff_hz;
  }
  line += "; motion faster than " + text(resolved_hz) + " Hz is not resolved";
  if (in.rate_hz < kLatchDetailRate_hz) {
    line += "; below " + text(kLatchDetailRate_hz) +
            " Hz the latch's details (release, snap and force edges lasting a few ms) are not "
            "resolved: they are averaged over two samples (" +
            milliseconds(2.0 * in.median_interval_s) +
            ") of travel, so latch angles and stiffnesses are approximate";
  }
  return line;
}

// Where the data come from: the source, the handle's radius and its origin, the sample
// rate, how the angle is obtained.
void describe_source(const Recording& recording, const Input& in, PreparedData& data) {
  data.source = recording.source;
  data.warnings = in.warnings;
  data.handle_radius_m = recording.handle_radius_m.value_or(0.0);
  for (const auto& [key, value] : recording.metadata) {
    if (key == kGeometryCalibrationKey) data.geometry_calibration_id = value;
  }
  if (data.handle_radius_m > 0) {
    data.handle_radius_origin =
        data.geometry_calibration_id.empty()
            ? "the recording's handle_radius_m"
            : "geometry record " + data.geometry_calibration_id +
                  " (the force corrected for the load cell's mounting angle)";
  }
  data.sample_rate_hz = recording.sample_rate_hz.value_or(in.rate_hz);
  switch (in.mode) {
    case Mode::kFused:
      data.angle_source = "rate_rad_s integrated, anchored to " + in.inclinometer_name;
      break;
    case Mode::kRateOnly:
      data.angle_source = "rate_rad_s integrated from theta = 0 at the first still period";
      break;
    case Mode::kAngleAndRate:
      data.angle_source = "angle_rad (full range); rate_rad_s with its bias taken from angle_rad";
      if (!in.inclinometer_name.empty()) {
        data.notes.push_back(in.inclinometer_name + " not used: angle_rad is the full-range angle");
      }
      break;
    case Mode::kAngleOnly:
      data.angle_source = "angle_rad (full range); rate: its zero-phase smoothed derivative";
      break;
  }
}

// The still periods trusted for the bias and the noise: the anchors' (in the
// inclinometer's range, or with a consistent bias), not a door creeping to rest at the
// open position; all still periods when no anchor has a bias.
std::vector<Range> trusted_periods(const std::vector<Anchor>& anchors, const Stillness& still) {
  std::vector<Range> trusted;
  for (const Anchor& anchor : anchors) {
    if (anchor.has_bias) trusted.push_back(anchor.period);
  }
  if (trusted.empty()) trusted = still.periods;
  return trusted;
}

// θ and ω: the rate integrated and anchored (which sets the anchors' offsets), or
// angle_rad and its derivative; and the note saying how.
Motion motion_of(const Input& in, std::vector<Anchor>& anchors,
                 const std::vector<double>& derived_rate, double derivative_cutoff_hz,
                 bool cutoff_auto, PreparedData& data) {
  Motion motion;
  if (in.has_rate) {
    motion = integrate_and_anchor(in, anchors);
  } else {
    motion.theta = in.angle;
    motion.omega = derived_rate;
  }
  data.gyro_bias_rad_s = motion.mean_bias;
  if (in.mode == Mode::kFused) {
    data.notes.push_back("theta anchored to " + in.inclinometer_name + " at " +
                         std::to_string(anchors.size()) + " still periods");
  } else if (in.mode == Mode::kRateOnly) {
    data.notes.push_back("no absolute angle: theta = 0 at the still period from " +
                         seconds(in.t[anchors.front().period.first]) +
                         ", taken for the closed door; the angle drifts with the bias error "
                         "from there");
  } else if (in.mode == Mode::kAngleOnly) {
    data.notes.push_back("rate: derivative of angle_rad after a zero-phase low-pass at " +
                         text(derivative_cutoff_hz) + " Hz" +
                         (cutoff_auto ? " (the rate's rule: min(30 Hz, sample rate / 4))" : ""));
  }
  return motion;
}

// The strokes to cut: the recording's stroke column (when used), else the motion's
// segments (those too short to be strokes go to `excluded`).
std::vector<Candidate> stroke_candidates(const Recording& recording, const Input& in,
                                         const Motion& motion, const Stillness& still,
                                         const PreprocessingOptions& options,
                                         std::vector<ExcludedSegment>& excluded) {
  if (recording.stroke && options.use_stroke_column) {
    return strokes_from_column(*recording.stroke);
  }
  const double noise = std::isfinite(still.noise_estimate) ? still.noise_estimate : 0.0;
  const double edge =
      std::min(options.motion_rate_rad_s, std::max(options.edge_rate_rad_s, 4.0 * noise));
  return segment_strokes(in.t, motion.theta, motion.omega, edge, options, excluded);
}

}  // namespace

PreparedData prepare(const Recording& recording, const PreprocessingOptions& options) {
  if (std::string problem = options.validate(); !problem.empty()) {
    throw std::invalid_argument(problem);
  }
  Input in = read_input(recording, options);
  PreparedData data;
  describe_source(recording, in, data);

  // The rate the stillness test looks at: the gyroscope's (bias included), or the
  // derivative of angle_rad.
  std::vector<double> derived_rate;
  const bool cutoff_auto = !(options.derivative_cutoff_hz > 0);
  const double derivative_cutoff_hz =
      cutoff_auto ? auto_derivative_cutoff_hz(in.rate_hz) : options.derivative_cutoff_hz;
  if (in.mode == Mode::kAngleOnly) {
    in.check_cutoff(derivative_cutoff_hz, "derivative_cutoff_hz");
    derived_rate = smoothing_derivative(in.t, in.angle, derivative_cutoff_hz, in.rate_hz);
    data.derivative_cutoff_hz = derivative_cutoff_hz;
  }
  data.interval_median_s = in.median_interval_s;
  data.interval_min_s = in.min_interval_s;
  data.interval_max_s = in.max_interval_s;
  data.jittered = in.jittered;
  data.rate_summary = describe_rate(in, data.derivative_cutoff_hz, cutoff_auto);
  const std::vector<double>& tested_rate = in.has_rate ? in.rate : derived_rate;
  const Stillness still = find_stillness(in, tested_rate, options);
  std::vector<Anchor> anchors = find_anchors(in, still, options);
  const std::vector<Range> trusted = trusted_periods(anchors, still);
  const Motion motion =
      motion_of(in, anchors, derived_rate, derivative_cutoff_hz, cutoff_auto, data);
  estimate_noise(in, still, trusted, anchors, tested_rate, options, data);
  apply_quantisation_floor(in, derivative_cutoff_hz, data);

  if (options.force_cutoff_hz > 0) {
    in.check_cutoff(options.force_cutoff_hz, "force_cutoff_hz");
    in.force = zero_phase_lowpass_at(in.t, in.force, options.force_cutoff_hz, in.rate_hz);
  }
  std::vector<ExcludedSegment> excluded;
  const std::vector<Candidate> candidates =
      stroke_candidates(recording, in, motion, still, options, excluded);
  cut_strokes(in, motion, anchors, candidates, options, data, excluded);
  std::stable_sort(
      excluded.begin(), excluded.end(),
      [](const ExcludedSegment& a, const ExcludedSegment& b) { return a.start_s < b.start_s; });
  data.excluded = std::move(excluded);
  return data;
}

PreparedData prepare_session(const std::filesystem::path& session_path,
                             const PreprocessingOptions& options) {
  const SessionReader session(session_path);
  return prepare(session_to_recording(session), options);
}

}  // namespace doorbench
