// What the stages of prepare() share (internal/prepare_stages.h).
#include <algorithm>
#include <cstdio>

#include "analysis/preprocessing/internal/prepare_stages.h"

namespace doorbench::preprocessing_detail {

std::string text(double value, int digits) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.*g", digits, value);
  return buffer;
}

std::string seconds(double value) {
  char buffer[48];
  std::snprintf(buffer, sizeof buffer, "%.3f s", value);
  return buffer;
}

double median(std::vector<double> values) {
  const std::size_t middle = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(middle),
                   values.end());
  double result = values[middle];
  if (values.size() % 2 == 0) {
    result =
        0.5 * (result + *std::max_element(values.begin(),
                                          values.begin() + static_cast<std::ptrdiff_t>(middle)));
  }
  return result;
}

std::size_t first_at_or_after(const std::vector<double>& time_s, double t) {
  return static_cast<std::size_t>(std::lower_bound(time_s.begin(), time_s.end(), t) -
                                  time_s.begin());
}

std::size_t last_at_or_before(const std::vector<double>& time_s, double t) {
  const auto after = std::upper_bound(time_s.begin(), time_s.end(), t);
  return after == time_s.begin() ? 0 : static_cast<std::size_t>(after - time_s.begin()) - 1;
}

}  // namespace doorbench::preprocessing_detail
