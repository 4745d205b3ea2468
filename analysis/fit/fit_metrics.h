#pragma once
// How well a door model reproduces prepared strokes (docs/fitting.md, "Metrics"):
//
// - on windows: each window simulated from its measured start state, as the fit sees it;
//   RMSE and largest error of ω, and FIT% = 100 (1 − ‖ω − ω̂‖ / ‖ω − mean(ω)‖);
// - replayed: each WHOLE stroke simulated open-loop from its first measured state under the
//   recorded force (the adaptive Dormand–Prince simulator); its largest error of ω is the
//   study's objective, max |ω_meas − ω_sim|.
//
// Errors are taken at every sample of a window that is not its start (windows; a window
// left out because it spans a recording gap measures none), or at every sample that is not
// the first of the stroke or of a part after a gap (replay, which restarts after a gap).
#include <string>
#include <vector>

#include "analysis/fit/fit_windows.h"
#include "analysis/model/door_model.h"
#include "analysis/preprocessing/strokes.h"

namespace doorbench {

// Sums from which RMSE, largest error and FIT% follow; strokes merge by adding.
struct ErrorStats {
  std::size_t count = 0;
  double sum_squared_error = 0.0;
  double max_abs_error = 0.0;
  double time_of_max_s = 0.0;  // on the recording's clock
  double sum_measured = 0.0;
  double sum_measured_squared = 0.0;

  void add(double measured, double simulated, double time_s);
  void merge(const ErrorStats& other);
  double rmse() const;
  // 100 (1 − ‖ω − ω̂‖ / ‖ω − mean(ω)‖); 100 is perfect, 0 is as good as the mean, and it
  // may be negative. NaN without samples or when ω is constant.
  double fit_percent() const;
};

struct StrokeFitMetrics {
  int stroke_id = 0;
  StrokeDirection direction = StrokeDirection::kOpening;
  std::size_t windows = 0;
  ErrorStats window;  // ω on windows
  ErrorStats replay;  // ω with the whole stroke replayed open-loop
  bool replay_ok = true;
  std::string replay_message;  // why the replay failed, when it did
};

struct FitMetrics {
  std::vector<StrokeFitMetrics> strokes;
  ErrorStats window;  // every stroke merged
  ErrorStats replay;  // strokes whose replay succeeded, merged
  int worst_window_stroke_id = 0;
  int worst_replay_stroke_id = 0;
  int failed_replays = 0;

  // The study's objective: the largest |ω_meas − ω_sim| over whole strokes replayed
  // open-loop (infinite when a replay failed).
  double study_objective_rad_s() const;
  void add(const StrokeFitMetrics& stroke);
};

// θ̂ and ω̂ of every stroke simulated window by window: at a window's first sample the
// measured state, elsewhere the simulation. `ok` is false where a window failed to
// integrate (its samples then hold NaN).
struct WindowSimulation {
  std::vector<std::vector<double>> theta_rad;
  std::vector<std::vector<double>> omega_rad_s;
  bool ok = true;
};

WindowSimulation simulate_windows(const DoorModel& model, const PreparedData& data,
                                  const WindowOptions& options);

// The windows of `options` left out because they span a recording gap (split_windows_and_gaps),
// each as an excluded segment from its first to its last sample, named for the user:
// "stroke 3 (opening): the window from 7.400 s to 7.600 s spans the recording gap from
// 7.499 s to 7.510 s and is not fitted". In stroke and time order.
std::vector<ExcludedSegment> gap_window_exclusions(const PreparedData& data,
                                                   const WindowOptions& options);

// Metrics of `model` on the strokes of `data` whose indices are listed (all when empty).
FitMetrics compute_fit_metrics(const DoorModel& model, const PreparedData& data,
                               const WindowOptions& options,
                               const std::vector<int>& stroke_indices = {});

// The window errors of `model` on every stroke of `data`, merged: compute_fit_metrics(...)
// .window to the last bit, without the replays (a screen of many models needs no more).
ErrorStats compute_window_errors(const DoorModel& model, const PreparedData& data,
                                 const WindowOptions& options);

}  // namespace doorbench
