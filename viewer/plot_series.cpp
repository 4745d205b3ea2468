#include "viewer/plot_series.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace doorbench::viewer {

namespace {

void take(double v, double& min, double& max) {
  // NaN compares false both ways and is skipped.
  if (v < min) min = v;
  if (v > max) max = v;
}

}  // namespace

MinMaxPyramid::MinMaxPyramid(const std::vector<double>& y) {
  std::size_t blocks = y.size() / kPyramidBlock;  // full blocks only; the tail is scanned
  if (blocks == 0) return;
  std::vector<double> mins(blocks, std::numeric_limits<double>::infinity());
  std::vector<double> maxs(blocks, -std::numeric_limits<double>::infinity());
  for (std::size_t b = 0; b < blocks; ++b) {
    const double* p = y.data() + b * kPyramidBlock;
    for (std::size_t i = 0; i < kPyramidBlock; ++i) take(p[i], mins[b], maxs[b]);
  }
  min_.push_back(std::move(mins));
  max_.push_back(std::move(maxs));
  // Level k+1 element i covers level-k elements 2i and 2i+1; an odd last one is left out
  // (queries never reach it at the upper level).
  while (min_.back().size() >= 2) {
    const auto& lower_min = min_.back();
    const auto& lower_max = max_.back();
    const std::size_t n = lower_min.size() / 2;
    std::vector<double> up_min(n), up_max(n);
    for (std::size_t i = 0; i < n; ++i) {
      up_min[i] = std::min(lower_min[2 * i], lower_min[2 * i + 1]);
      up_max[i] = std::max(lower_max[2 * i], lower_max[2 * i + 1]);
    }
    min_.push_back(std::move(up_min));
    max_.push_back(std::move(up_max));
  }
}

void MinMaxPyramid::range(const std::vector<double>& y, std::size_t begin, std::size_t end,
                          double& min, double& max) const {
  min = std::numeric_limits<double>::infinity();
  max = -std::numeric_limits<double>::infinity();
  if (begin >= end) return;
  const std::size_t first_block = (begin + kPyramidBlock - 1) / kPyramidBlock;
  const std::size_t end_block = end / kPyramidBlock;
  if (min_.empty() || first_block >= end_block) {
    for (std::size_t i = begin; i < end; ++i) take(y[i], min, max);
    return;
  }
  for (std::size_t i = begin; i < first_block * kPyramidBlock; ++i) take(y[i], min, max);
  for (std::size_t i = end_block * kPyramidBlock; i < end; ++i) take(y[i], min, max);
  // Bottom-up over the levels: the odd ends of [lo, hi) at each level, then go up.
  std::size_t lo = first_block, hi = end_block;
  for (std::size_t level = 0; lo < hi; ++level) {
    const auto& mins = min_[level];
    const auto& maxs = max_[level];
    if (level + 1 == min_.size()) {
      for (std::size_t i = lo; i < hi; ++i) {
        min = std::min(min, mins[i]);
        max = std::max(max, maxs[i]);
      }
      break;
    }
    if (lo & 1) {
      min = std::min(min, mins[lo]);
      max = std::max(max, maxs[lo]);
      ++lo;
    }
    if (hi & 1) {
      --hi;
      min = std::min(min, mins[hi]);
      max = std::max(max, maxs[hi]);
    }
    lo /= 2;
    hi /= 2;
  }
}

Series::Series(std::string name, std::string x_unit, std::string unit, Kind kind)
    : name_(std::move(name)), x_unit_(std::move(x_unit)), unit_(std::move(unit)), kind_(kind) {}

Series Series::uniform(std::string name, std::string unit, double x0, double dx,
                       std::vector<double> y) {
  if (!(dx > 0.0) || !std::isfinite(dx) || !std::isfinite(x0)) {
    throw std::invalid_argument(
        std::string("series '")
            .append(name)
            .append("': a uniform clock needs a finite start and a step > 0"));
  }
  Series s(std::move(name), "s", std::move(unit), Kind::kUniform);
  s.x0_ = x0;
  s.dx_ = dx;
  s.y_ = std::move(y);
  s.build();
  return s;
}

Series Series::timed(std::string name, std::string unit, std::vector<double> x,
                     std::vector<double> y) {
  if (x.size() != y.size()) {
    throw std::invalid_argument(
        std::string("series '").append(name).append("': x and y have different lengths"));
  }
  for (std::size_t i = 1; i < x.size(); ++i) {
    if (!(x[i] >= x[i - 1])) {
      throw std::invalid_argument(std::string("series '")
                                      .append(name)
                                      .append("': times decrease at sample ")
                                      .append(std::to_string(i)));
    }
  }
  Series s(std::move(name), "s", std::move(unit), Kind::kTimed);
  s.x_ = std::move(x);
  s.y_ = std::move(y);
  s.build();
  return s;
}

Series Series::xy(std::string name, std::string x_unit, std::string unit, std::vector<double> x,
                  std::vector<double> y) {
  if (x.size() != y.size()) {
    throw std::invalid_argument(
        std::string("series '").append(name).append("': x and y have different lengths"));
  }
  Series s(std::move(name), std::move(x_unit), std::move(unit), Kind::kXy);
  s.x_ = std::move(x);
  s.y_ = std::move(y);
  return s;
}

Series Series::shifted(double dx, std::string name) const {
  Series s = *this;
  s.name_ = std::move(name);
  if (kind_ == Kind::kUniform) {
    s.x0_ += dx;
  } else {
    for (double& v : s.x_) v += dx;
  }
  return s;
}

void Series::build() {
  pyramid_ = MinMaxPyramid(y_);
}

std::size_t Series::lower_index(double value) const {
  const std::size_t n = y_.size();
  if (kind_ == Kind::kXy) throw std::logic_error("lower_index on an x-y series");
  if (kind_ == Kind::kTimed) {
    return std::size_t(std::lower_bound(x_.begin(), x_.end(), value) - x_.begin());
  }
  const double guess = std::ceil((value - x0_) / dx_);
  std::size_t i = guess <= 0.0 ? 0 : guess >= double(n) ? n : std::size_t(guess);
  // The guess can be one off by rounding; settle it against x(i) itself.
  while (i > 0 && x(i - 1) >= value) --i;
  while (i < n && x(i) < value) ++i;
  return i;
}

void Series::index_range(double x_min, double x_max, std::size_t& begin, std::size_t& end) const {
  begin = lower_index(x_min);
  end = begin;
  const std::size_t n = y_.size();
  // The first index with x > x_max.
  if (kind_ == Kind::kTimed) {
    end = std::size_t(std::upper_bound(x_.begin(), x_.end(), x_max) - x_.begin());
  } else {
    end = lower_index(x_max);
    while (end < n && x(end) <= x_max) ++end;
  }
  if (end < begin) end = begin;
}

void Series::y_range(std::size_t begin, std::size_t end, double& min, double& max) const {
  if (kind_ == Kind::kXy) {
    min = std::numeric_limits<double>::infinity();
    max = -std::numeric_limits<double>::infinity();
    for (std::size_t i = begin; i < end; ++i) take(y_[i], min, max);
    return;
  }
  pyramid_.range(y_, begin, end, min, max);
}

void Series::bounds(double& x_min, double& x_max, double& y_min, double& y_max) const {
  x_min = y_min = std::numeric_limits<double>::infinity();
  x_max = y_max = -std::numeric_limits<double>::infinity();
  if (y_.empty()) return;
  y_range(0, y_.size(), y_min, y_max);
  if (kind_ == Kind::kXy) {
    for (double v : x_) {
      if (std::isfinite(v)) take(v, x_min, x_max);
    }
  } else {
    x_min = x(0);
    x_max = x(y_.size() - 1);
  }
}

std::size_t Series::nearest(double xq, double yq, double x_scale, double y_scale) const {
  const std::size_t n = y_.size();
  if (n == 0) return 0;
  if (kind_ != Kind::kXy) {
    const std::size_t i = lower_index(xq);
    if (i == 0) return 0;
    if (i == n) return n - 1;
    return (xq - x(i - 1) <= x(i) - xq) ? i - 1 : i;
  }
  std::size_t best = n;
  double best_d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = (x_[i] - xq) * x_scale;
    const double dy = (y_[i] - yq) * y_scale;
    const double d = dx * dx + dy * dy;
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

std::vector<Column> decimate(const Series& series, double x_min, double x_max,
                             std::size_t width_px) {
  std::vector<Column> columns;
  decimate_into(series, x_min, x_max, width_px, columns);
  return columns;
}

void decimate_into(const Series& series, double x_min, double x_max, std::size_t width_px,
                   std::vector<Column>& columns) {
  if (series.is_xy()) {
    throw std::invalid_argument(std::string("decimate: '")
                                    .append(series.name())
                                    .append("' is an x-y series, not a time series"));
  }
  if (width_px == 0) throw std::invalid_argument("decimate: width_px must be > 0");
  if (!std::isfinite(x_min) || !std::isfinite(x_max) || !(x_max > x_min)) {
    throw std::invalid_argument("decimate: the x-range must be finite with x_max > x_min");
  }
  columns.assign(width_px, Column{});
  const double span = x_max - x_min;
  std::size_t begin = series.lower_index(x_min);
  std::size_t range_begin = 0, range_end = 0;
  series.index_range(x_min, x_max, range_begin, range_end);
  for (std::size_t c = 0; c < width_px; ++c) {
    std::size_t end = c + 1 == width_px
                          ? range_end
                          : series.lower_index(x_min + span * (double(c + 1) / double(width_px)));
    end = std::min(std::max(end, begin), range_end);
    Column& column = columns[c];
    if (end > begin) {
      column.count = end - begin;
      column.first = series.y(begin);
      column.last = series.y(end - 1);
      series.y_range(begin, end, column.min, column.max);
    }
    begin = end;
  }
}

}  // namespace doorbench::viewer
