#include "analysis/fit/fit_windows.h"

#include <algorithm>
#include <cmath>

#include "analysis/fit/internal/window_residual.h"
#include "core/percentile.h"

namespace doorbench {

namespace {

// Whether `window` has one of the (increasing) `gaps` between two of its samples.
bool spans_gap(const FitWindow& window, const std::vector<int>& gaps) {
  const auto gap = std::upper_bound(gaps.begin(), gaps.end(), window.first);
  return gap != gaps.end() && *gap <= window.first + window.count - 1;
}

// Windows over samples [begin, end) of one stroke, a piece without impacts. A short last
// window joins the one before it unless one of them spans a gap (both would be left out).
void split_piece(int stroke_index, const Stroke& stroke, int begin, int end, double window_s,
                 bool disjoint, const std::vector<int>& gaps, std::vector<FitWindow>& windows) {
  if (end - begin < 2) return;
  const std::size_t first_of_piece = windows.size();
  int start = begin;
  while (start < end - 1) {
    int last = start + 1;
    while (last < end - 1 && stroke.time_s[last] - stroke.time_s[start] < window_s) ++last;
    windows.push_back({stroke_index, start, last - start + 1});
    start = disjoint ? last + 1 : last;
  }
  // Disjoint windows can leave one sample over: it joins the last window.
  if (disjoint && start == end - 1 && windows.size() > first_of_piece) ++windows.back().count;
  // A short last piece joins the window before it (in the same piece).
  if (windows.size() - first_of_piece >= 2) {
    const FitWindow tail = windows.back();
    const double tail_s = stroke.time_s[tail.first + tail.count - 1] - stroke.time_s[tail.first];
    if (tail_s < 0.5 * window_s && !spans_gap(tail, gaps) &&
        !spans_gap(windows[windows.size() - 2], gaps)) {
      windows.pop_back();
      windows.back().count += tail.count - (disjoint ? 0 : 1);
    }
  }
}

}  // namespace

std::vector<int> stroke_gaps(const Stroke& stroke) {
  std::vector<int> gaps;
  const int n = static_cast<int>(stroke.size());
  if (n < 2) return gaps;
  const double gap_s = kWindowGapFactor * median_interval_s(stroke.time_s);
  for (int i = 1; i < n; ++i) {
    const bool marked = std::binary_search(stroke.gap_before.begin(), stroke.gap_before.end(), i);
    if (marked || stroke.time_s[i] - stroke.time_s[i - 1] > gap_s) gaps.push_back(i);
  }
  return gaps;
}

WindowSplit split_windows_and_gaps(const PreparedData& data, const WindowOptions& options) {
  WindowSplit split;
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    const Stroke& stroke = data.strokes[s];
    const int n = static_cast<int>(stroke.size());
    if (n < 2) continue;
    const std::vector<int> gaps = stroke_gaps(stroke);
    const double window_s = options.whole_strokes ? INFINITY : options.window_s;
    auto impact = [&](int i) {
      if (std::abs(stroke.omega_rad_s[i - 1]) <= options.cut_rate_rad_s ||
          std::abs(stroke.omega_rad_s[i]) <= options.cut_rate_rad_s) {
        return false;
      }
      for (double angle : options.cut_angles_rad) {
        if ((stroke.theta_rad[i - 1] - angle) * (stroke.theta_rad[i] - angle) <= 0) return true;
      }
      return false;
    };
    // Whole strokes are cut at gaps as at impacts (a replay restarts after one); windows
    // are laid over gaps as if the samples were there, and those that span one are left out.
    std::vector<FitWindow> windows;
    int begin = 0;
    for (int i = 1; i < n; ++i) {
      const bool gap = std::binary_search(gaps.begin(), gaps.end(), i);
      if ((options.whole_strokes && gap) || impact(i)) {
        split_piece(static_cast<int>(s), stroke, begin, i, window_s, options.disjoint, gaps,
                    windows);
        begin = i;
      }
    }
    split_piece(static_cast<int>(s), stroke, begin, n, window_s, options.disjoint, gaps, windows);
    for (const FitWindow& window : windows) {
      (spans_gap(window, gaps) ? split.across_gaps : split.windows).push_back(window);
    }
  }
  return split;
}

std::vector<FitWindow> split_windows(const PreparedData& data, const WindowOptions& options) {
  return split_windows_and_gaps(data, options).windows;
}

std::vector<double> ParameterMap::values(const double* x) const {
  std::vector<double> full(base_values.size());
  fill(x, full.data());
  return full;
}

std::vector<double> ParameterMap::scaled(const std::vector<double>& values) const {
  std::vector<double> x(free_index.size());
  for (std::size_t k = 0; k < free_index.size(); ++k) x[k] = values[free_index[k]] / scale[k];
  return x;
}

int window_residual_count(const WindowResidualSetup& setup, const FitWindow& window) {
  return (window.count - 1) * (setup.angle_residuals ? 2 : 1) +
         (setup.estimate_start_state ? 2 : 0);
}

ceres::CostFunction* make_window_cost(const WindowResidualSetup& setup, const FitWindow& window) {
  // The Jacobian takes ceil(active / Stride) passes of Jets with Stride derivative parts:
  // pick the stride that needs one pass for the usual sizes without wasting many parts. A
  // loop's refit adds one to three effect parameters to the default 13-14 (17-19 with the
  // window states): one pass of 24 instead of two of 16.
  const int free = setup.map->free_count() + (setup.estimate_start_state ? 2 : 0);
  if (free <= 4) return fit_detail::make_cost<4>(setup, window);
  if (free <= 8) return fit_detail::make_cost<8>(setup, window);
  if (free <= 16) return fit_detail::make_cost<16>(setup, window);
  return fit_detail::make_wide_window_cost(setup, window);
}

}  // namespace doorbench
