#pragma once
// The percentile of a sample by linear interpolation between order statistics (R's
// quantile(type = 7), numpy's default): with the n values sorted, fraction f sits at
// position f·(n−1), between the values either side of it.
//
//   percentile(values, f)             sorts a copy of `values`
//   percentile_of_sorted(sorted, f)   `sorted` already in ascending order (no copy, no sort)
//   median(values)                    the middle value, or the mean of the two middle ones
//                                     (percentile(values, 0.5) up to rounding; linear time)
//   median_interval_s(time_s)         the median of the steps between consecutive times (a
//                                     recording's sampling interval; kNaN for fewer than 2)
//
// Contract: an empty sample has no percentile and no median: the result is kNaN (core/numbers.h),
// never an exception or a read out of range. f is clamped to [0, 1] (0 the smallest value, 1 the
// largest); a NaN f gives kNaN. The values must not hold NaN (their order is not defined).
// Pure functions: safe from any thread.
#include <span>
#include <vector>

namespace doorbench {

double percentile(std::vector<double> values, double fraction);
double percentile_of_sorted(std::span<const double> sorted, double fraction);
double median(std::vector<double> values);
double median_interval_s(std::span<const double> time_s);

}  // namespace doorbench
