#pragma once
// Placing channels of different clocks on one time axis for analysis
// (docs/synchronization.md): linear interpolation between a channel's own samples, no
// extrapolation beyond its first and last sample, and no bridging of gaps: a time that
// falls between two samples further apart than the gap limit gets NaN. The recorded
// samples are never changed; this is done on read (session_to_recording).
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace doorbench {

struct Recording;

// The gap limit of a channel: kGapIntervals × its median sampling interval
// (core/percentile.h's median_interval_s).
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

// The metadata key resample_recording adds: how the recording was resampled.
inline constexpr std::string_view kResampledMetadataKey = "import_resampled";

// The recording on a uniform clock of rate_hz from its first time to its last (import
// --resample-hz; docs/csv-format.md, "Resampling on import"). Each column: slower than the
// recording (rate_hz below 1 / its median interval), each new sample is the mean of the
// recorded ones within half a new interval of its time, [t - 0.5/rate_hz, t + 0.5/rate_hz)
// (a boxcar against aliasing), missing (NaN) when none is there or one of them is missing;
// otherwise linear interpolation, missing across a gap of more than kGapIntervals median
// intervals. The stroke of each new sample is that of the latest recorded sample at or
// before its time. Says how in the metadata (kResampledMetadataKey). Throws
// std::runtime_error naming the source for fewer than two samples.
Recording resample_recording(const Recording& in, double rate_hz);

}  // namespace doorbench
