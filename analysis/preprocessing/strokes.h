#pragma once
// A prepared recording: strokes (one opening or one closing each) with the door's angle
// and rate on the full range, and the handle force, ready for fitting. Preprocessing makes
// these from a session or a CSV; fitting consumes them.
#include <string>
#include <vector>

namespace doorbench {

enum class StrokeDirection { kOpening, kClosing };

struct Stroke {
  int id = 0;  // the recording's stroke id (or a running number)
  StrokeDirection direction = StrokeDirection::kOpening;
  std::vector<double> time_s;       // strictly increasing, on the recording's clock
  std::vector<double> force_N;      // F_u at the handle, positive = opening
  std::vector<double> theta_rad;    // full-range angle (fused)
  std::vector<double> omega_rad_s;  // rate (bias removed)
  // Recording gaps inside the stroke: each i (>= 1, increasing) such that samples were lost
  // (a ring overflow), or the clock jumps, between time_s[i - 1] and time_s[i]. The samples
  // around a gap are kept; the fit leaves out every window that spans one
  // (analysis/fit/fit_windows.h).
  std::vector<int> gap_before;
  std::size_t size() const { return time_s.size(); }
};

// A segment left out of the prepared data, and why (saturated gyroscope, a fault, too short).
struct ExcludedSegment {
  double start_s = 0.0;
  double end_s = 0.0;
  std::string reason;
  bool lost_samples = false;  // it holds samples lost in recording (a gap): said on stderr
};

struct PreparedData {
  std::string source;            // the session or CSV it came from
  double handle_radius_m = 0.0;  // from the data's metadata, when known (else 0)
  // The geometry record whose handle radius this is (and which corrected the force for the
  // load cell's mounting angle); empty when there is none.
  std::string geometry_calibration_id;
  // Where handle_radius_m came from, for reports ("geometry record ID (...)", "the
  // recording's handle_radius_m"; readers of files may name the file's field); empty when
  // the data states no radius.
  std::string handle_radius_origin;
  double sample_rate_hz = 0.0;
  std::vector<Stroke> strokes;
  std::vector<ExcludedSegment> excluded;
  // Noise levels the weights of a fit use (estimated from still periods, or the bench's).
  double angle_noise_rad = 0.0;
  double rate_noise_rad_s = 0.0;
  // How the angle was obtained (e.g. "gyroscope anchored to inclinometer_angle_rad"), the
  // gyroscope bias removed (its mean over the recording; 0 without a gyroscope), and the
  // assumptions made (e.g. theta = 0 at the first still period when there is no angle).
  std::string angle_source;
  double gyro_bias_rad_s = 0.0;
  std::vector<std::string> notes;
  // Physically impossible samples left out (channel, how many, when, the largest value):
  // fit and loop print each on stderr as "warning: ...".
  std::vector<std::string> warnings;
  // The sampling as found (docs/preprocessing.md, "Any sample rate"): the intervals'
  // median, smallest and largest (s); jittered when an interval differs from the median by
  // more than 1% (the filters then work on a uniform grid); the derivative's cut-off used
  // (0: no derivative taken); one line saying what this rate resolves, for reports.
  double interval_median_s = 0.0;
  double interval_min_s = 0.0;
  double interval_max_s = 0.0;
  bool jittered = false;
  double derivative_cutoff_hz = 0.0;
  std::string rate_summary;
};

}  // namespace doorbench
