#pragma once
// Tuning (no GL, no ImGui): a door model's parameters and, for the sensory model, the
// perceptual controls (analysis/perceptual_controls.h, spec §2) changed one at a time; each
// change re-simulates the selected strokes open-loop under their recorded force (the
// study's replay, analysis/fit_metrics.h) so that the tuned ω can be seen against the
// measured one; reset to the fitted values; save as a new parameter file.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "analysis/door_model.h"
#include "analysis/perceptual_controls.h"
#include "analysis/strokes.h"
#include "viewer/plot_view.h"

namespace doorbench::viewer {

class Tuning {
 public:
  // `strokes`: indices into data.strokes to re-simulate (empty: at most the first 12).
  // Throws std::invalid_argument when there is no stroke or an index is out of range.
  Tuning(const PreparedData& data, DoorModel fitted, std::vector<int> strokes = {});

  const DoorModel& fitted() const { return fitted_; }
  const DoorModel& model() const { return model_; }
  std::size_t stroke_count() const { return data_.strokes.size(); }

  // "" when the change was made; otherwise the model's one-line reason, and nothing changes.
  std::string set_parameter(int index, double value);
  std::string set_control(perceptual::Control control, double value);
  void reset() { model_ = fitted_; }

  // Replays the selected strokes with the current model and updates the plot; returns the
  // wall time it took in ms. A stroke whose replay fails shows as a gap.
  double resimulate();
  double last_resimulate_ms() const { return last_ms_; }
  // Strokes are replayed in parallel on up to this many threads (default: the cores);
  // each stroke's replay is independent, so the result does not depend on it.
  void set_threads(int threads) { threads_ = threads < 1 ? 1 : threads; }
  int threads() const { return threads_; }
  // Largest |ω_meas − ω_sim| over the replayed strokes (the study's objective), rad/s.
  double max_error_rad_s() const { return max_error_; }

  // Measured ω, the fitted model's and the tuned model's replay; strokes one after another.
  PlotView plot;

  // Writes the tuned model as a parameter file at `params_path` and, when it has effects,
  // its effects file next to it (stem + "-effects.json"); returns the paths written.
  std::vector<std::filesystem::path> save(const std::filesystem::path& params_path) const;

 private:
  std::shared_ptr<Series> replay(const DoorModel& model, const std::string& name, Rgba colour,
                                 double* max_error);
  PreparedData data_;  // the selected strokes only
  // The same strokes one per PreparedData, so that each replays on its own thread.
  std::vector<PreparedData> singles_;
  int threads_ = 1;
  DoorModel fitted_;
  DoorModel model_;
  double last_ms_ = 0.0;
  double max_error_ = 0.0;
};

}  // namespace doorbench::viewer
