// What the stages of prepare() share (internal/prepare_stages.h).
#include "analysis/preprocessing/internal/prepare_stages.h"

#include <algorithm>
#include <cstdio>

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

std::size_t first_at_or_after(const std::vector<double>& time_s, double t) {
  return static_cast<std::size_t>(std::lower_bound(time_s.begin(), time_s.end(), t) -
                                  time_s.begin());
}

std::size_t last_at_or_before(const std::vector<double>& time_s, double t) {
  const auto after = std::upper_bound(time_s.begin(), time_s.end(), t);
  return after == time_s.begin() ? 0 : static_cast<std::size_t>(after - time_s.begin()) - 1;
}

}  // namespace doorbench::preprocessing_detail
