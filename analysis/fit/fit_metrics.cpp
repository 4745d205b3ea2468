#include "analysis/fit/fit_metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <utility>

#include "analysis/simulation/simulator.h"

namespace doorbench {

void ErrorStats::add(double measured, double simulated, double time_s) {
  const double error = simulated - measured;
  ++count;
  sum_squared_error += error * error;
  sum_measured += measured;
  sum_measured_squared += measured * measured;
  // NaN (a failed simulation) counts as the largest error.
  if (!(std::abs(error) <= max_abs_error)) {
    max_abs_error = std::isnan(error) ? std::numeric_limits<double>::infinity() : std::abs(error);
    time_of_max_s = time_s;
  }
}

void ErrorStats::merge(const ErrorStats& other) {
  if (other.max_abs_error > max_abs_error || count == 0) {
    max_abs_error = other.max_abs_error;
    time_of_max_s = other.time_of_max_s;
  }
  count += other.count;
  sum_squared_error += other.sum_squared_error;
  sum_measured += other.sum_measured;
  sum_measured_squared += other.sum_measured_squared;
}

double ErrorStats::rmse() const {
  if (count == 0) return std::numeric_limits<double>::quiet_NaN();
  return std::sqrt(sum_squared_error / static_cast<double>(count));
}

double ErrorStats::fit_percent() const {
  if (count == 0) return std::numeric_limits<double>::quiet_NaN();
  const double n = static_cast<double>(count);
  const double spread = sum_measured_squared - sum_measured * sum_measured / n;
  if (!(spread > 0)) return std::numeric_limits<double>::quiet_NaN();
  return 100.0 * (1.0 - std::sqrt(sum_squared_error / spread));
}

double FitMetrics::study_objective_rad_s() const {
  if (failed_replays > 0) return std::numeric_limits<double>::infinity();
  return replay.max_abs_error;
}

void FitMetrics::add(const StrokeFitMetrics& stroke) {
  if (strokes.empty() || stroke.window.max_abs_error > window.max_abs_error) {
    worst_window_stroke_id = stroke.stroke_id;
  }
  window.merge(stroke.window);
  if (stroke.replay_ok) {
    if (replay.count == 0 || stroke.replay.max_abs_error > replay.max_abs_error) {
      worst_replay_stroke_id = stroke.stroke_id;
    }
    replay.merge(stroke.replay);
  } else {
    if (failed_replays == 0) worst_replay_stroke_id = stroke.stroke_id;
    ++failed_replays;
  }
  strokes.push_back(stroke);
}

WindowSimulation simulate_windows(const DoorModel& model, const PreparedData& data,
                                  const WindowOptions& options) {
  WindowSimulation out;
  out.theta_rad.resize(data.strokes.size());
  out.omega_rad_s.resize(data.strokes.size());
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    out.theta_rad[s] = data.strokes[s].theta_rad;
    out.omega_rad_s[s] = data.strokes[s].omega_rad_s;
  }
  const std::span<const double> parameters = model.parameter_values();
  for (const FitWindow& window : split_windows(data, options)) {
    const Stroke& stroke = data.strokes[window.stroke];
    std::vector<double>& theta = out.theta_rad[window.stroke];
    std::vector<double>& omega = out.omega_rad_s[window.stroke];
    auto sink = [&](int j, double theta_sim, double omega_sim) {
      theta[window.first + j] = theta_sim;
      omega[window.first + j] = omega_sim;
    };
    for (int j = 1; j < window.count; ++j) {  // NaN unless the integration gets there
      theta[window.first + j] = omega[window.first + j] = std::numeric_limits<double>::quiet_NaN();
    }
    if (!integrate_window(model, parameters.data(), stroke, window, options.substeps_per_sample,
                          stroke.theta_rad[window.first], stroke.omega_rad_s[window.first], sink)) {
      out.ok = false;
    }
  }
  return out;
}

std::vector<ExcludedSegment> gap_window_exclusions(const PreparedData& data,
                                                   const WindowOptions& options) {
  std::vector<ExcludedSegment> out;
  for (const FitWindow& window : split_windows_and_gaps(data, options).across_gaps) {
    const Stroke& stroke = data.strokes[window.stroke];
    const std::vector<int> gaps = stroke_gaps(stroke);
    const int last = window.first + window.count - 1;
    const int gap = *std::upper_bound(gaps.begin(), gaps.end(), window.first);
    char text[200];
    std::snprintf(text, sizeof text,
                  "stroke %d (%s): the window from %.3f s to %.3f s spans the recording gap "
                  "from %.3f s to %.3f s and is not fitted",
                  stroke.id, stroke.direction == StrokeDirection::kOpening ? "opening" : "closing",
                  stroke.time_s[window.first], stroke.time_s[last], stroke.time_s[gap - 1],
                  stroke.time_s[gap]);
    out.push_back({stroke.time_s[window.first], stroke.time_s[last], text, true});
  }
  return out;
}

namespace {

// The stroke replayed open-loop from its first measured state; after a gap in the recording
// (stroke_gaps) the replay restarts from the measured state there, as a new stroke would.
void replay_stroke(const DoorModel& model, const Stroke& stroke, StrokeFitMetrics& metrics) {
  if (stroke.size() < 2) return;
  std::vector<int> starts = stroke_gaps(stroke);
  starts.insert(starts.begin(), 0);
  starts.push_back(static_cast<int>(stroke.size()));
  try {
    for (std::size_t p = 0; p + 1 < starts.size(); ++p) {
      const auto first = static_cast<std::ptrdiff_t>(starts[p]);
      const auto end = static_cast<std::ptrdiff_t>(starts[p + 1]);
      if (end - first < 2) continue;
      const std::vector<double> time_s(stroke.time_s.begin() + first, stroke.time_s.begin() + end);
      const RecordedForce force(time_s, std::vector<double>(stroke.force_N.begin() + first,
                                                            stroke.force_N.begin() + end));
      DoorState initial;
      initial.time_s = time_s.front();
      initial.theta_rad = stroke.theta_rad[first];
      initial.omega_rad_s = stroke.omega_rad_s[first];
      const Trajectory run = simulate(model, force, initial, time_s);
      for (std::ptrdiff_t i = 1; i < end - first; ++i) {
        const auto k = static_cast<std::size_t>(first + i);
        metrics.replay.add(stroke.omega_rad_s[k], run.omega_rad_s[static_cast<std::size_t>(i)],
                           stroke.time_s[k]);
      }
    }
  } catch (const std::exception& error) {
    metrics.replay_ok = false;
    metrics.replay_message = error.what();
  }
}

// Each listed stroke's window errors (every stroke's when `stroke_indices` is empty), in the
// order listed, and every stroke's window count in `window_count`; a stroke of fewer than two
// samples has no errors and is left out.
std::vector<std::pair<int, ErrorStats>> stroke_window_errors(
    const DoorModel& model, const PreparedData& data, const WindowOptions& options,
    const std::vector<int>& stroke_indices, std::vector<std::size_t>& window_count) {
  std::vector<int> indices = stroke_indices;
  if (indices.empty()) {
    for (std::size_t s = 0; s < data.strokes.size(); ++s) indices.push_back(static_cast<int>(s));
  }
  const WindowSimulation windows = simulate_windows(model, data, options);
  // The samples measured: those in a window but not its first (a window left out because
  // it spans a gap measures none).
  window_count.assign(data.strokes.size(), 0);
  std::vector<std::vector<char>> counted(data.strokes.size());
  for (std::size_t s = 0; s < data.strokes.size(); ++s) {
    counted[s].assign(data.strokes[s].size(), 0);
  }
  const std::vector<FitWindow> windows_used = split_windows(data, options);
  for (const FitWindow& window : windows_used) {
    ++window_count[window.stroke];
    for (int j = 1; j < window.count; ++j) counted[window.stroke][window.first + j] = 1;
  }
  for (const FitWindow& window : windows_used) counted[window.stroke][window.first] = 0;
  std::vector<std::pair<int, ErrorStats>> out;
  for (int s : indices) {
    if (s < 0 || s >= static_cast<int>(data.strokes.size())) {
      throw std::out_of_range("compute_fit_metrics: no stroke at index " + std::to_string(s));
    }
    const Stroke& stroke = data.strokes[s];
    if (stroke.size() < 2) continue;  // nothing to compare
    ErrorStats errors;
    for (std::size_t i = 0; i < stroke.size(); ++i) {
      if (!counted[s][i]) continue;
      errors.add(stroke.omega_rad_s[i], windows.omega_rad_s[s][i], stroke.time_s[i]);
    }
    out.emplace_back(s, errors);
  }
  return out;
}

}  // namespace

FitMetrics compute_fit_metrics(const DoorModel& model, const PreparedData& data,
                               const WindowOptions& options,
                               const std::vector<int>& stroke_indices) {
  std::vector<std::size_t> window_count;
  FitMetrics metrics;
  for (const auto& [s, errors] :
       stroke_window_errors(model, data, options, stroke_indices, window_count)) {
    const Stroke& stroke = data.strokes[s];
    StrokeFitMetrics stroke_metrics;
    stroke_metrics.stroke_id = stroke.id;
    stroke_metrics.direction = stroke.direction;
    stroke_metrics.windows = window_count[s];
    stroke_metrics.window = errors;
    replay_stroke(model, stroke, stroke_metrics);
    metrics.add(stroke_metrics);
  }
  return metrics;
}

ErrorStats compute_window_errors(const DoorModel& model, const PreparedData& data,
                                 const WindowOptions& options) {
  std::vector<std::size_t> window_count;
  ErrorStats all;
  for (const auto& [s, errors] : stroke_window_errors(model, data, options, {}, window_count)) {
    all.merge(errors);
  }
  return all;
}

}  // namespace doorbench
