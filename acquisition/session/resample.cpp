#include "acquisition/session/resample.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace doorbench {

double median_interval_s(std::span<const double> time_s) {
  if (time_s.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  std::vector<double> intervals(time_s.size() - 1);
  for (std::size_t i = 1; i < time_s.size(); ++i) intervals[i - 1] = time_s[i] - time_s[i - 1];
  const auto middle = intervals.begin() + static_cast<std::ptrdiff_t>(intervals.size() / 2);
  std::nth_element(intervals.begin(), middle, intervals.end());
  if (intervals.size() % 2 == 1) return *middle;
  const double upper = *middle;
  const double lower = *std::max_element(intervals.begin(), middle);
  return (lower + upper) / 2;
}

std::vector<double> resample_linear(std::span<const double> time_s, std::span<const double> values,
                                    std::span<const double> at, double max_gap_s,
                                    const std::string& what) {
  if (time_s.size() != values.size()) {
    throw std::invalid_argument(what + ": " + std::to_string(time_s.size()) + " times but " +
                                std::to_string(values.size()) + " values");
  }
  if (!(max_gap_s > 0)) throw std::invalid_argument(what + ": the gap limit must be > 0");
  for (std::size_t i = 1; i < time_s.size(); ++i) {
    if (!(time_s[i] > time_s[i - 1])) {
      throw std::invalid_argument(what + ": sample times do not increase at sample " +
                                  std::to_string(i));
    }
  }
  std::vector<double> out(at.size(), std::numeric_limits<double>::quiet_NaN());
  std::size_t k = 0;  // time_s[k] <= t < time_s[k + 1] for the current t
  for (std::size_t j = 0; j < at.size(); ++j) {
    const double t = at[j];
    if (j > 0 && !(t >= at[j - 1])) {
      throw std::invalid_argument(what + ": the target times do not increase at " +
                                  std::to_string(j));
    }
    if (time_s.empty() || t < time_s.front() || t > time_s.back()) continue;
    while (k + 1 < time_s.size() && time_s[k + 1] <= t) ++k;
    if (time_s[k] == t) {
      out[j] = values[k];
      continue;
    }
    const double span = time_s[k + 1] - time_s[k];
    if (span > max_gap_s) continue;  // a gap: marked, not bridged
    const double s = (t - time_s[k]) / span;
    out[j] = values[k] + s * (values[k + 1] - values[k]);
  }
  return out;
}

std::vector<double> uniform_axis(double start_s, double end_s, double rate_hz) {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("uniform axis: rate must be > 0");
  }
  std::vector<double> axis;
  if (!(end_s >= start_s)) return axis;
  const auto count = static_cast<std::size_t>(std::floor((end_s - start_s) * rate_hz + 1e-9)) + 1;
  axis.reserve(count);
  for (std::size_t i = 0; i < count; ++i)
    axis.push_back(start_s + static_cast<double>(i) / rate_hz);
  while (!axis.empty() && axis.back() > end_s) axis.pop_back();
  return axis;
}

}  // namespace doorbench
