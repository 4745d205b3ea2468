#pragma once
// The stages of prepare() and what they pass on (analysis/preprocessing/ only): the
// recording read and checked (Input, faults_and_anchoring.cpp), the stillness test and the
// anchors, the angle integrated and anchored (Motion), the stroke cutter
// (stroke_cutter.cpp), the noise estimate (noise.cpp), and the few helpers they share.
// docs/preprocessing.md. Pure functions of their arguments, safe on any thread; errors are
// PreprocessingError with the message "SOURCE: ...".
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "analysis/preprocessing/preprocessing.h"
#include "core/percentile.h"

namespace doorbench::preprocessing_detail {

// A number as text with `digits` significant digits (%g), and seconds with three decimals
// ("1.250 s"), for the messages and notes.
std::string text(double value, int digits = 3);
std::string seconds(double value);

// Sample fault kinds (bits).
enum Fault : std::uint8_t {
  kSaturated = 1,
  kRateNonFinite = 2,
  kAngleNonFinite = 4,
  kForceNonFinite = 8,
  kGapBefore = 16,   // the interval ending at this sample is a gap
  kLost = 32,        // every measured column missing: a scan lost in recording (a gap)
  kImpossible = 64,  // a value beyond the physical limits (PreprocessingOptions::max_abs_*)
};

struct Range {
  std::size_t first = 0, last = 0;  // inclusive sample indices
};

// The first sample at or after `t`, and the last at or before it (0 when none), in the
// increasing `time_s`.
std::size_t first_at_or_after(const std::vector<double>& time_s, double t);
std::size_t last_at_or_before(const std::vector<double>& time_s, double t);

enum class Mode { kFused, kRateOnly, kAngleAndRate, kAngleOnly };

struct Anchor {
  Range period;  // the still period (bias from here)
  Range region;  // where the absolute angle is compared (offset from here)
  double time_s = 0;
  std::size_t index = 0;  // the region's middle sample
  double bias = 0;
  bool has_bias = true;
  double offset = 0;
};

struct Candidate {
  Range range;
  int id = 0;
};

// The recording's columns, checked, with the method chosen, faults marked and non-finite
// values bridged (they are never used as values: a stroke holding one is left out).
struct Input {
  std::string source;
  Mode mode = Mode::kFused;
  bool has_rate = false;
  std::vector<double> t, force, rate, angle, incl;  // rate, angle, incl: empty when absent
  std::string inclinometer_name;
  std::vector<std::uint8_t> fault;
  std::vector<std::string> warnings;       // physically impossible samples, per channel
  std::vector<std::uint8_t> motion_fault;  // fault without a bad force alone (stillness test)
  // unknown[i] counts the intervals in (0, i] over which the rate is unknown: saturated or
  // non-finite at either end, or a gap.
  std::vector<std::size_t> unknown;
  double median_interval_s = 0;
  double min_interval_s = 0, max_interval_s = 0;
  bool jittered = false;  // an interval differs from the median by more than kJitterFraction
  double rate_hz = 0;     // 1 / median interval: what the filters use
  double saturation_limit = 0;

  std::size_t size() const { return t.size(); }
  void check_cutoff(double cutoff_hz, const char* name) const {
    if (!(cutoff_hz < 0.5 * rate_hz)) {
      throw PreprocessingError(source + ": " + name + " " + text(cutoff_hz) +
                               " Hz is not below half the sample rate (" + text(0.5 * rate_hz) +
                               " Hz)");
    }
  }
};

struct Stillness {
  double noise_estimate = 0;  // σ̂ of the tested rate (NaN when no block qualified)
  double rate_std_limit = 0;
  std::vector<Range> periods;
  std::string rule;  // the test with its thresholds, for messages
};

struct Motion {
  std::vector<double> theta, omega;
  double mean_bias = 0;  // of the bias removed from the rate
};

// The filters (filters.cpp): smoothing_derivative on samples already at uniform times.
std::vector<double> uniform_derivative(std::span<const double> time_s,
                                       std::span<const double> values, double cutoff_hz,
                                       double sample_rate_hz);

// Fault marking and anchoring (faults_and_anchoring.cpp).
// The recording's columns checked, the method chosen, faults marked, non-finite values
// bridged.
Input read_input(const Recording& recording, const PreprocessingOptions& options);
// The stillness test on `rate` (its noise estimated, its periods found).
Stillness find_stillness(const Input& in, const std::vector<double>& rate,
                         const PreprocessingOptions& options);
// Anchors: still periods where the absolute angle is known (for the rate only: the still
// periods with a consistent bias), each with a bias sample (the mean rate over the period).
// Throws when the method needs an anchor and there is none.
std::vector<Anchor> find_anchors(const Input& in, const Stillness& still,
                                 const PreprocessingOptions& options);
// The bias piecewise-linear through the anchors' bias samples, the rate integrated
// (trapezoid), and the drift removed between the anchors (docs/preprocessing.md). Sets each
// anchor's offset; for the rate only, keeps just the first anchor (theta = 0 there).
Motion integrate_and_anchor(const Input& in, std::vector<Anchor>& anchors);

// The stroke cutter (stroke_cutter.cpp).
// Motion segments of ω (see PreprocessingOptions, segmentation). Segments too short to be
// strokes go to `excluded`. Ids are 1, 2, … in time order.
std::vector<Candidate> segment_strokes(const std::vector<double>& time_s,
                                       const std::vector<double>& theta,
                                       const std::vector<double>& omega, double edge_rate,
                                       const PreprocessingOptions& options,
                                       std::vector<ExcludedSegment>& excluded);
// The strokes of the recording's stroke column (ids as in the column).
std::vector<Candidate> strokes_from_column(const std::vector<int>& stroke);
// Cuts the strokes out of the motion into `data`: one candidate at a time, leaving out (and
// listing) those with faults, with an unknown angle, or too short; then lists the faulty
// samples outside every stroke.
void cut_strokes(const Input& in, const Motion& motion, const std::vector<Anchor>& anchors,
                 const std::vector<Candidate>& candidates, const PreprocessingOptions& options,
                 PreparedData& data, std::vector<ExcludedSegment>& excluded);

// The noise estimate (noise.cpp).
// Robust white-noise level of a signal: the median over blocks of kNoiseBlock samples
// (skipping blocks with faulty samples) of the variance about a fitted straight line.
// NaN when no block qualifies.
double robust_noise(const std::vector<double>& values, const std::vector<std::uint8_t>& faults);
// Noise levels from the trusted still periods, else the bench's figures.
void estimate_noise(const Input& in, const Stillness& still, const std::vector<Range>& trusted,
                    const std::vector<Anchor>& anchors, const std::vector<double>& tested_rate,
                    const PreprocessingOptions& options, PreparedData& data);
// A quantised angle (an encoder's steps) that stands still reads no noise at all: its
// noise is at least the quantisation's, q / sqrt(12), and so is the derivative's.
void apply_quantisation_floor(const Input& in, double derivative_cutoff_hz, PreparedData& data);

}  // namespace doorbench::preprocessing_detail
