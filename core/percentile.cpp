#include "core/percentile.h"

#include <algorithm>
#include <cmath>

#include "core/numbers.h"

namespace doorbench {

double percentile(std::vector<double> values, double fraction) {
  std::sort(values.begin(), values.end());
  return percentile_of_sorted(values, fraction);
}

double percentile_of_sorted(std::span<const double> sorted, double fraction) {
  if (sorted.empty() || std::isnan(fraction)) return kNaN;
  const double position = std::clamp(fraction, 0.0, 1.0) * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (position - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

double median(std::vector<double> values) {
  if (values.empty()) return kNaN;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  if (values.size() % 2 == 1) return *middle;
  // The lower middle value is the largest of the half before `middle`.
  return 0.5 * (*std::max_element(values.begin(), middle) + *middle);
}

double median_interval_s(std::span<const double> time_s) {
  if (time_s.size() < 2) return kNaN;
  std::vector<double> intervals(time_s.size() - 1);
  for (std::size_t i = 1; i < time_s.size(); ++i) intervals[i - 1] = time_s[i] - time_s[i - 1];
  return median(std::move(intervals));
}

}  // namespace doorbench
