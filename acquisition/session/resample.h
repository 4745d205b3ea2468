#pragma once
// Placing channels of different clocks on one time axis for analysis
// (docs/synchronization.md): linear interpolation between a channel's own samples, no
// extrapolation beyond its first and last sample, and no bridging of gaps: a time that
// falls between two samples further apart than the gap limit gets NaN. The recorded
// samples are never changed; this is done on read (session_to_recording).
#include <span>
#include <string>
#include <vector>

namespace doorbench {

// The median of the intervals between consecutive times; NaN with fewer than two times.
double median_interval_s(std::span<const double> time_s);

// The gap limit of a channel: kGapIntervals × its median sampling interval.
inline constexpr double kGapIntervals = 3.0;

// `values` (at strictly increasing `time_s`) at each of the increasing times `at`:
// linearly interpolated between the two samples around it (a sample's own time gives the
// sample exactly); NaN before the first or after the last sample, or when the two samples
// around it are more than `max_gap_s` apart. Throws std::invalid_argument naming `what`
// for sizes that differ, times that do not increase, or max_gap_s <= 0.
std::vector<double> resample_linear(std::span<const double> time_s, std::span<const double> values,
                                    std::span<const double> at, double max_gap_s,
                                    const std::string& what = "channel");

// start_s, start_s + 1/rate_hz, … up to end_s (inclusive, to a part in 1e9 of a period).
std::vector<double> uniform_axis(double start_s, double end_s, double rate_hz);

}  // namespace doorbench
